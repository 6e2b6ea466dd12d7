// The localization study's oracle (docs/experiments/localization.md): the OSM way of a SUMO lane,
// the true edges a SUMO sample may be on (the lane's way, a joined junction, a way netconvert
// joined to the next), and the RMSE over the samples our graph has a road for.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "localizer/study/localization_study.hpp"
#include "tests/localizer/sketch_graph.hpp"

namespace corridor::localizer {
namespace {

using testing::Sketch;
using testing::edge_between;

TEST(LocalizationStudy, ReadsTheOsmWayOfASumoLane) {
  EXPECT_EQ(sumo_lane_osm_way("93209286#3_0"), 93209286);
  EXPECT_EQ(sumo_lane_osm_way("-93209286#12_1"), 93209286);
  EXPECT_EQ(sumo_lane_osm_way("4230011_0"), 4230011);
  EXPECT_FALSE(sumo_lane_osm_way(":cluster_1_0_0"));
  EXPECT_FALSE(sumo_lane_osm_way("93137621#0-AddedOnRampEdge_1"));
  EXPECT_FALSE(sumo_lane_osm_way("93209286#3"));
  EXPECT_FALSE(sumo_lane_osm_way(""));
}

// A SUMO sample at (x, y) in the local frame, heading east, on `lane`.
TruthSample eastward_sample(const maps::RoadGraph& g, double x, double y, const char* lane) {
  TruthSample t;
  t.position = g.projection().to_lat_lon({x, y});
  t.heading_deg = 90.0;
  t.lane = lane;
  return t;
}

// The oracle: a lane of way 1 names that way's edge even where way 3 runs nearer, and inside a
// junction either the edge before it or the one after it is the truth.
TEST(LocalizationStudy, TrueEdgesFollowTheLaneWayAndSpanAJunction) {
  Sketch s;
  // Way 1 west-east into the junction (0,0), way 2 on to the east; way 3 a parallel street 4 m
  // north of way 1, joined to the junction by way 4.
  s.nodes = {{-300, 0}, {0, 0}, {300, 0}, {-300, 4}, {-10, 4}};
  s.roads = {{{0, 1}, false, 1}, {{1, 2}, false, 2}, {{3, 4}, false, 3}, {{4, 1}, false, 4}};
  const auto g = s.build();
  const maps::EdgeSnapper snapper(g);
  auto sample = [&](double x, double y, const char* lane) { return eastward_sample(g, x, y, lane); };
  const std::vector<TruthSample> drive = {sample(-100, 3.5, "1_0"), sample(-1, 0, ":J_0_0"), sample(100, 0, "2_0"),
                                          sample(-50, 3.9, "")};
  const auto truth = true_edges(g, snapper, drive, 20.0);
  const EdgeId way1 = edge_between(g, {-300, 0}, {0, 0}), way2 = edge_between(g, {0, 0}, {300, 0});
  EXPECT_EQ(truth[0].edge, way1);  // nearer to way 3, but on way 1's lane
  EXPECT_TRUE(truth[1].contains(way1));
  EXPECT_TRUE(truth[1].contains(way2));
  EXPECT_EQ(truth[2].edge, way2);
  EXPECT_EQ(truth[3].edge, edge_between(g, {-300, 4}, {-10, 4}));  // no lane: the nearest road
}

// netconvert joins way 1 and way 2, which meet end to end with no junction, into one edge whose lane
// names way 1 only. A vehicle on that lane 3 m past the node has driven onto way 2, though way 1's
// end lies within 4 m; one 0.5 m short of the node is still on way 1.
TEST(LocalizationStudy, ALanePastItsWaysEndIsOnTheWayJoinedToIt) {
  Sketch s;
  s.nodes = {{-300, 0}, {0, 0}, {300, 0}};
  s.roads = {{{0, 1}, false, 1}, {{1, 2}, false, 2}};
  const auto g = s.build();
  const maps::EdgeSnapper snapper(g);
  const std::vector<TruthSample> drive = {eastward_sample(g, 3, 1.6, "1_0"), eastward_sample(g, -0.5, 1.6, "1_0")};
  const auto truth = true_edges(g, snapper, drive, 20.0);
  EXPECT_EQ(truth[0].edge, edge_between(g, {0, 0}, {300, 0}));
  EXPECT_EQ(truth[1].edge, edge_between(g, {-300, 0}, {0, 0}));
}

// A way that bends back on itself (a hairpin) has no end near a sample half-way round, though the
// sample lies behind its first piece: its lane still names it, with a tunnel 1 m below it nearer.
TEST(LocalizationStudy, AHairpinsLaneIsOnItsWayAllTheWayRound) {
  maps::GraphBuildInput in;
  in.origin = {47.0, 9.5};
  in.node_pos = {{0, 0}, {-50, 20}, {20, 21}, {-60, 21}};
  for (std::uint32_t i = 0; i < 4; ++i) {
    in.node_osm.push_back(OsmNodeId{i + 1});
    in.node_signalized.push_back(0);
  }
  auto road = [&](std::uint32_t from, std::uint32_t to, std::vector<maps::Point2> points, std::int64_t way) {
    maps::RoadSegment seg;
    seg.from = from;
    seg.to = to;
    seg.first_point = static_cast<std::uint32_t>(in.points.size());
    in.points.insert(in.points.end(), points.begin(), points.end());
    seg.last_point = static_cast<std::uint32_t>(in.points.size() - 1);
    seg.forward = true;
    seg.forward_speed_mps = seg.backward_speed_mps = 14.0f;
    seg.way = OsmWayId{way};
    seg.road_class = maps::RoadClass::residential;
    in.segments.push_back(seg);
  };
  road(0, 1, {{0, 0}, {100, 0}, {100, 20}, {-50, 20}}, 1);  // east, round, and back west
  road(2, 3, {{20, 21}, {-60, 21}}, 2);                      // the tunnel, west
  const maps::RoadGraph g = maps::build_road_graph(in);
  const maps::EdgeSnapper snapper(g);
  TruthSample t = eastward_sample(g, -30, 20.6, "1_0");
  t.heading_deg = 270.0;
  const auto truth = true_edges(g, snapper, {t}, 20.0);
  ASSERT_TRUE(truth[0].edge.valid());
  EXPECT_EQ(g.osm_way(truth[0].edge).v, 1);
}

// SUMO drives some ways our importer leaves out (a street closed to motor vehicles): a sample on
// such a way's lane has no true edge, though one of our roads runs 4 m from it.
TEST(LocalizationStudy, ALaneOnAWayTheGraphLacksHasNoTrueEdge) {
  Sketch s;
  s.nodes = {{-300, 0}, {300, 0}};
  s.roads = {{{0, 1}, false, 1}};
  const auto g = s.build();
  const maps::EdgeSnapper snapper(g);
  const std::vector<TruthSample> drive = {eastward_sample(g, 0, 4, "7_0"), eastward_sample(g, 10, 4, "1_0")};
  const auto truth = true_edges(g, snapper, drive, 20.0);
  EXPECT_FALSE(truth[0].valid());
  EXPECT_TRUE(truth[0].nearest.valid());  // the nearest road is still reported, for comparison
  EXPECT_EQ(truth[1].edge, edge_between(g, {-300, 0}, {300, 0}));
}

// SUMO joins OSM nodes a few metres apart into one junction (a divided road's crossing): a vehicle
// inside it may be on the short OSM edge between them, which is then part of the truth too; the
// way back and a street leaving the junction are not.
TEST(LocalizationStudy, AJoinedJunctionCountsTheShortEdgesInsideIt) {
  Sketch s;
  s.nodes = {{-300, 0}, {0, 0}, {8, 0}, {300, 0}, {0, -100}, {8, 100}};
  s.roads = {{{0, 1}, false, 1}, {{1, 2}, false, 5}, {{2, 3}, false, 2}, {{4, 1}, false, 3}, {{2, 5}, false, 4}};
  const auto g = s.build();
  const maps::EdgeSnapper snapper(g);
  auto sample = [&](double x, double y, const char* lane) { return eastward_sample(g, x, y, lane); };
  const std::vector<TruthSample> drive = {sample(-50, 0, "1_0"), sample(4, 0, ":cluster_2_3_0_0"), sample(50, 0, "2_0")};
  const auto truth = true_edges(g, snapper, drive, 20.0);
  EXPECT_TRUE(truth[1].contains(edge_between(g, {-300, 0}, {0, 0})));
  EXPECT_TRUE(truth[1].contains(edge_between(g, {0, 0}, {8, 0})));
  EXPECT_TRUE(truth[1].contains(edge_between(g, {8, 0}, {300, 0})));
  EXPECT_FALSE(truth[1].contains(edge_between(g, {8, 0}, {0, 0})));   // the way back
  EXPECT_FALSE(truth[1].contains(edge_between(g, {8, 0}, {8, 100})));  // a street leaving the junction
  EXPECT_FALSE(truth[0].contains(edge_between(g, {0, 0}, {8, 0})));    // outside it, one edge
}

// A joined cluster on a fast road can be longer than the fixed allowance (60 m): here 80 m, with
// three OSM edges inside, crossed in three samples. The roads between may be as long as the
// vehicle drove from the sample before the junction to the one after it.
TEST(LocalizationStudy, ALongJoinedJunctionCountsEveryEdgeTheVehicleCrossed) {
  Sketch s;
  s.nodes = {{-300, 0}, {0, 0}, {40, 0}, {80, 0}, {400, 0}, {40, 100}};
  s.roads = {{{0, 1}, false, 1}, {{1, 2}, false, 5}, {{2, 3}, false, 6}, {{3, 4}, false, 2}, {{2, 5}, false, 4}};
  const auto g = s.build();
  const maps::EdgeSnapper snapper(g);
  auto sample = [&](double x, const char* lane) { return eastward_sample(g, x, 0, lane); };
  const std::vector<TruthSample> drive = {sample(-30, "1_0"), sample(10, ":cluster_1_2_3_0_0"), sample(45, ":cluster_1_2_3_0_0"),
                                          sample(75, ":cluster_1_2_3_0_0"), sample(110, "2_0")};
  const auto truth = true_edges(g, snapper, drive, 20.0);
  for (std::size_t i = 1; i <= 3; ++i) {
    EXPECT_TRUE(truth[i].contains(edge_between(g, {0, 0}, {40, 0}))) << i;
    EXPECT_TRUE(truth[i].contains(edge_between(g, {40, 0}, {80, 0}))) << i;
    EXPECT_FALSE(truth[i].contains(edge_between(g, {40, 0}, {40, 100}))) << i;  // a street leaving it
  }
}

// A drive that leaves our graph (SUMO keeps a way our importer drops): its samples there have no
// true edge, and the on-graph RMSE leaves out the errors no matcher on our graph could avoid.
TEST(LocalizationStudy, TheOnGraphRmseLeavesOutSamplesOffOurGraph) {
  Sketch s;
  // East to (0, 0), then north; from (0, 25) a street runs east, parallel to the drive's line on.
  s.nodes = {{-600, 0}, {0, 0}, {0, 25}, {0, 300}, {400, 25}};
  s.roads = {{{0, 1}, false, 1}, {{1, 2, 3}, false, 2}, {{2, 4}, false, 3}};
  const auto g = s.build();
  const maps::EdgeSnapper snapper(g);
  std::vector<TruthSample> drive;
  for (int k = 0; k <= 60; ++k) {
    // 10 m/s east along the road, and from x = 0 on straight on, where our graph has no road: the
    // nearest is the parallel street 25 m away, beyond the truth's radius (20 m).
    TruthSample t = eastward_sample(g, -405.0 + 10.0 * k, 0.0, "1_0");
    t.time_s = k;
    t.speed_mps = 10.0;
    drive.push_back(t);
  }
  StudyConfig config;
  config.noise_sigma_m = 2.0;
  config.outlier_share = 0.0;
  config.outage_s = 0.0;
  const auto result = run_localization_study(g, snapper, {{"probe", drive}}, config);
  const DriveResult& d = result.total;
  EXPECT_EQ(d.n_raw, drive.size());
  EXPECT_EQ(d.with_truth, 43u);  // x <= 15 m: the first road within the truth radius (20 m)
  ASSERT_GT(d.n_hmm_on_graph, 30u);
  EXPECT_LT(d.n_hmm_on_graph, d.n_hmm);
  // Off the road the match is on the parallel street, 25 m away; on it, the error is the noise's,
  // except where the drive passes the corner (0, 0) and the match has turned already.
  const double on_graph = std::sqrt(d.sq_hmm_on_graph / static_cast<double>(d.n_hmm_on_graph));
  const double all = std::sqrt(d.sq_hmm / static_cast<double>(d.n_hmm));
  EXPECT_GT(all, 10.0);
  EXPECT_LT(on_graph, 0.6 * all);
}

}  // namespace
}  // namespace corridor::localizer
