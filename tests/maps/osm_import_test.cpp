#include "maps/osm_import.hpp"

#include <gtest/gtest.h>
#include <zlib.h>

#include <cmath>
#include <fstream>

#include "maps/edge_snapper.hpp"
#include "maps/errors.hpp"
#include "maps/osm_tags.hpp"
#include "tests/maps/osm_fixture.hpp"

namespace corridor::maps {
namespace {

using testing::at;
using testing::FixtureNode;
using testing::FixtureWay;
using testing::TempDir;
using testing::write_osm;

NodeId node_by_osm(const RoadGraph& g, long long osm) {
  for (NodeId v : g.nodes()) {
    if (g.osm_node(v).v == osm) return v;
  }
  return kInvalidNode;
}

EdgeId edge_between(const RoadGraph& g, long long from, long long to) {
  const NodeId a = node_by_osm(g, from);
  const NodeId b = node_by_osm(g, to);
  if (!a.valid() || !b.valid()) return kInvalidEdge;
  for (EdgeId e : g.out_edges(a)) {
    if (g.head(e) == b) return e;
  }
  return kInvalidEdge;
}

RoadGraph import_fixture(const std::vector<FixtureNode>& nodes, const std::vector<FixtureWay>& ways,
                         OsmImportReport* report = nullptr) {
  TempDir dir;
  const auto file = dir.path() / "fixture.osm";
  write_osm(file, nodes, ways);
  OsmImportOptions options;
  options.show_progress = false;
  return import_osm(file, options, report);
}

const std::map<std::string, std::string> kResidential{{"highway", "residential"}};

TEST(OsmImport, DegreeTwoChainsBecomeOneEdgeWithGeometry) {
  // Way 1: 1-2-3-4-5 along the x axis; way 2 leaves node 3 northward, so 3 is a junction.
  const auto g = import_fixture({at(1, 0, 0), at(2, 50, 0), at(3, 100, 0), at(4, 150, 0), at(5, 200, 0), at(6, 100, 80)},
                                {{10, {1, 2, 3, 4, 5}, kResidential}, {11, {3, 6}, kResidential}});
  EXPECT_EQ(g.node_count(), 4u);  // 1, 3, 5, 6: nodes 2 and 4 are geometry only
  EXPECT_EQ(g.edge_count(), 6u);
  const EdgeId e = edge_between(g, 1, 3);
  ASSERT_TRUE(e.valid());
  EXPECT_EQ(g.geometry(e).size(), 3u);
  EXPECT_NEAR(g.length_m(e), 100.0, 0.5);
  EXPECT_EQ(g.osm_way(e).v, 10);
  EXPECT_TRUE(g.twin(e).valid());
  EXPECT_EQ(g.head(g.twin(e)), g.tail(e));
  EXPECT_FALSE(node_by_osm(g, 2).valid());
}

TEST(OsmImport, OnewayWaysGetOneDirectedEdge) {
  // A one-way triangle 1->2->3->1, and a two-way street 1-4 so the triangle has an exit.
  const std::map<std::string, std::string> oneway{{"highway", "residential"}, {"oneway", "yes"}};
  const std::map<std::string, std::string> reverse{{"highway", "residential"}, {"oneway", "-1"}};
  const auto g = import_fixture({at(1, 0, 0), at(2, 100, 0), at(3, 50, 90), at(4, -100, 0)},
                                {{20, {1, 2}, oneway}, {21, {2, 3}, oneway}, {22, {1, 3}, reverse}, {23, {1, 4}, kResidential}});
  EXPECT_TRUE(edge_between(g, 1, 2).valid());
  EXPECT_FALSE(edge_between(g, 2, 1).valid());
  EXPECT_TRUE(edge_between(g, 2, 3).valid());
  EXPECT_FALSE(edge_between(g, 3, 2).valid());
  EXPECT_TRUE(edge_between(g, 3, 1).valid());  // oneway=-1 against the way's node order
  EXPECT_FALSE(edge_between(g, 1, 3).valid());
  EXPECT_FALSE(g.twin(edge_between(g, 1, 2)).valid());
  EXPECT_TRUE(edge_between(g, 1, 4).valid() && edge_between(g, 4, 1).valid());
}

TEST(OsmImport, RoundaboutIsOnewayInWayOrder) {
  const std::map<std::string, std::string> ring{{"highway", "primary"}, {"junction", "roundabout"}};
  const auto g = import_fixture({at(1, 0, 0), at(2, 30, 30), at(3, 0, 60), at(4, -30, 30), at(5, 0, -100), at(6, 0, 160)},
                                {{30, {1, 2, 3, 4, 1}, ring}, {31, {5, 1}, kResidential}, {32, {3, 6}, kResidential}});
  const EdgeId forward = edge_between(g, 1, 3);
  ASSERT_TRUE(forward.valid());
  EXPECT_EQ(g.geometry(forward).size(), 3u);  // 1 -> 2 -> 3
  EXPECT_TRUE(edge_between(g, 3, 1).valid());  // onward via 4
  EXPECT_EQ(g.geometry(edge_between(g, 3, 1)).size(), 3u);
  EXPECT_FALSE(g.twin(forward).valid());
  for (EdgeId e : g.edges()) {
    if (g.osm_way(e).v == 30) {
      EXPECT_FALSE(g.twin(e).valid());
    }
  }
}

TEST(OsmImport, MaxspeedBecomesEdgeSpeed) {
  const auto g = import_fixture({at(1, 0, 0), at(2, 100, 0), at(3, 200, 0)},
                                {{40, {1, 2}, {{"highway", "secondary"}, {"maxspeed", "30 mph"}}},
                                 {41, {2, 3}, {{"highway", "secondary"}}}});
  EXPECT_NEAR(g.speed_mps(edge_between(g, 1, 2)), 30 * 1.609344 / 3.6, 1e-5);
  EXPECT_NEAR(g.speed_mps(edge_between(g, 2, 3)), default_speed_kmh(RoadClass::secondary) / 3.6, 1e-5);
  EXPECT_EQ(g.road_class(edge_between(g, 2, 3)), RoadClass::secondary);
}

// A ferry's duration is the whole crossing's: each piece of the way runs at the way's length over
// it. A click beside the berth snaps to the quay road when trip ends skip ferries; a vehicle's own
// fix may still land on the ferry.
TEST(OsmImport, FerryDurationSpreadsOverTheWayAndTripEndsSkipFerries) {
  const auto g = import_fixture({at(1, 0, 0), at(2, 100, 0), at(3, 200, 0), at(4, 300, 0), at(5, 200, 50)},
                                {{40, {1, 2}, kResidential},
                                 {41, {2, 3, 4}, {{"route", "ferry"}, {"duration", "0:03"}}},
                                 {42, {3, 5}, kResidential}});
  const EdgeId first = edge_between(g, 2, 3), second = edge_between(g, 3, 4);
  ASSERT_TRUE(first.valid() && second.valid());
  EXPECT_EQ(g.road_class(first), RoadClass::ferry);
  EXPECT_NEAR(g.length_m(first) / g.speed_mps(first) + g.length_m(second) / g.speed_mps(second), 180.0, 0.01);
  const EdgeSnapper snapper(g);
  const LatLon beside_berth = g.projection().to_lat_lon(g.position(node_by_osm(g, 4)));
  EXPECT_EQ(g.road_class(snapper.snap(beside_berth).edge), RoadClass::ferry);
  SnapOptions trip_end;
  trip_end.skip_ferries = true;
  const SnapResult quay = snapper.snap(beside_berth, trip_end);
  EXPECT_NE(g.road_class(quay.edge), RoadClass::ferry);
  EXPECT_EQ(g.osm_way(quay.edge).v, 42);
}

TEST(OsmImport, AccessNoAndFootwaysAreExcluded) {
  const auto g = import_fixture(
      {at(1, 0, 0), at(2, 100, 0), at(3, 200, 0), at(4, 100, 100), at(5, 0, 100)},
      {{50, {1, 2, 3}, kResidential},
       {51, {2, 4}, {{"highway", "residential"}, {"access", "no"}}},
       {52, {1, 5}, {{"highway", "footway"}}},
       {53, {3, 5}, {{"highway", "footway"}, {"emergency", "yes"}}}});
  EXPECT_FALSE(node_by_osm(g, 4).valid());
  EXPECT_TRUE(edge_between(g, 3, 5).valid());  // emergency access road
  EXPECT_FALSE(edge_between(g, 1, 5).valid());
}

TEST(OsmImport, KeepsEveryComponentAndMarksTheLargestAsMain) {
  // A one-way spur 3 -> 7 leaves and never returns, and 8-9 joins nothing: both are kept, since a
  // route may end on the spur and a click may land on either. Only 1, 3 and 4 form the main
  // component. Node 2 lies inside way 60 and is no graph node; node 10 is on no way.
  OsmImportReport report;
  const auto g = import_fixture({at(1, 0, 0), at(2, 100, 0), at(3, 200, 0), at(4, 0, 100), at(7, 300, 0), at(8, 5000, 5000),
                                 at(9, 5100, 5000), at(10, 200, 200)},
                                {{60, {1, 2, 3}, kResidential},
                                 {63, {1, 4}, kResidential},
                                 {61, {3, 7}, {{"highway", "residential"}, {"oneway", "yes"}}},
                                 {62, {8, 9}, kResidential}},
                                &report);
  EXPECT_EQ(g.node_count(), 6u);  // 1, 3, 4, 7, 8 and 9
  EXPECT_EQ(report.graph.dropped_nodes, 0u);
  EXPECT_EQ(report.graph.input_nodes, 6u);
  EXPECT_EQ(report.graph.components, 3u);  // {1, 3, 4}, {7}, {8, 9}
  EXPECT_EQ(report.graph.largest_component_nodes, 3u);
  EXPECT_EQ(g.main_component_nodes(), 3u);
  EXPECT_EQ(g.runner_up_component_nodes(), 2u);
  for (long long osm : {1, 3, 4}) EXPECT_TRUE(g.in_main_component(node_by_osm(g, osm))) << osm;
  for (long long osm : {7, 8, 9}) EXPECT_FALSE(g.in_main_component(node_by_osm(g, osm))) << osm;
  ASSERT_TRUE(edge_between(g, 3, 7).valid());
  EXPECT_FALSE(edge_between(g, 7, 3).valid());
  EXPECT_FALSE(g.in_main_component(edge_between(g, 3, 7)));
  EXPECT_TRUE(g.in_main_component(edge_between(g, 1, 3)));
  EXPECT_FALSE(g.in_main_component(edge_between(g, 8, 9)));
}

// Landmarks go to the main component, however many cut-off roads the map has: a node no landmark
// reaches would otherwise win every round of the farthest selection, and 20 islands would take all
// 16 landmarks, where they bound nothing.
TEST(OsmImport, LandmarksLieOnTheMainComponentWhateverTheCutOffRoads) {
  std::vector<FixtureNode> nodes;
  std::vector<FixtureWay> ways;
  // The main component: a 6 x 6 grid of two-way streets, 100 m apart (every node a junction).
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) nodes.push_back(at(1 + r * 6 + c, c * 100.0, r * 100.0));
  }
  for (int i = 0; i < 6; ++i) {
    std::vector<long long> row, column;
    for (int j = 0; j < 6; ++j) {
      row.push_back(1 + i * 6LL + j);
      column.push_back(1 + j * 6LL + i);
    }
    ways.push_back({10 + i, row, kResidential});
    ways.push_back({20 + i, column, kResidential});
  }
  for (int i = 0; i < 20; ++i) {
    nodes.push_back(at(1000 + 2 * i, i * 100.0, 5000));
    nodes.push_back(at(1001 + 2 * i, i * 100.0 + 50, 5000));
    ways.push_back({100 + i, {1000 + 2LL * i, 1001 + 2LL * i}, kResidential});
  }
  const auto g = import_fixture(nodes, ways);
  ASSERT_EQ(g.main_component_nodes(), 36u);
  ASSERT_EQ(g.landmark_count(), kDefaultLandmarkCount);
  for (NodeId l : g.data().landmarks.nodes) EXPECT_TRUE(g.in_main_component(l)) << l.v;
}

TEST(OsmImport, SignalsAtAndNearJunctionsMarkTheJunction) {
  const std::map<std::string, std::string> signal{{"highway", "traffic_signals"}};
  // Junction 3 has a signal 20 m before it on way 70; junction 5 carries the tag itself; the signal
  // at node 11 is 150 m from any junction and marks nothing.
  const auto g = import_fixture(
      {at(1, 0, 0), at(2, 180, 0, signal), at(3, 200, 0), at(4, 200, 100), at(5, 400, 0, signal), at(6, 400, 100),
       at(10, 0, 300), at(11, 150, 300, signal), at(12, 300, 300)},
      {{70, {1, 2, 3, 5}, kResidential},
       {71, {3, 4}, kResidential},
       {72, {5, 6}, kResidential},
       {73, {1, 10}, kResidential},
       {74, {10, 11, 12, 6}, kResidential}});
  EXPECT_TRUE(g.signalized(node_by_osm(g, 3)));
  EXPECT_TRUE(g.signalized(node_by_osm(g, 5)));
  EXPECT_FALSE(g.signalized(node_by_osm(g, 1)));
  EXPECT_FALSE(g.signalized(node_by_osm(g, 10)));
  EXPECT_FALSE(g.signalized(node_by_osm(g, 6)));
}

TEST(OsmImport, WaysCutByTheExtractBorderAreSplit) {
  // Node 99 is not in the file (outside the extract); the way continues on both sides of it.
  const auto g = import_fixture({at(1, 0, 0), at(2, 100, 0), at(3, 200, 0), at(4, 300, 0), at(5, 100, 100), at(6, 200, 100)},
                                {{80, {1, 2, 99, 3, 4}, kResidential}, {81, {2, 5, 6, 3}, kResidential}});
  EXPECT_TRUE(edge_between(g, 1, 2).valid());
  EXPECT_TRUE(edge_between(g, 3, 4).valid());
  // 2 and 3 are joined only by way 81, around the missing node, never straight across the gap.
  const EdgeId e = edge_between(g, 2, 3);
  ASSERT_TRUE(e.valid());
  EXPECT_EQ(g.osm_way(e).v, 81);
  EXPECT_NEAR(g.length_m(e), 300.0, 1.0);
}

TEST(OsmImport, ReadsGzipCompressedXml) {
  TempDir dir;
  const auto plain = dir.path() / "a.osm";
  write_osm(plain, {at(1, 0, 0), at(2, 100, 0)}, {{90, {1, 2}, kResidential}});
  std::ifstream in(plain, std::ios::binary);
  const std::string xml((std::istreambuf_iterator<char>(in)), {});
  const auto gz = dir.path() / "a.osm.gz";
  gzFile out = gzopen(gz.c_str(), "wb");
  ASSERT_NE(out, nullptr);
  ASSERT_EQ(gzwrite(out, xml.data(), static_cast<unsigned>(xml.size())), static_cast<int>(xml.size()));
  gzclose(out);
  OsmImportOptions options;
  options.show_progress = false;
  const auto g = import_osm(gz, options);
  EXPECT_EQ(g.node_count(), 2u);
  EXPECT_EQ(g.edge_count(), 2u);
}

TEST(OsmImport, MissingFileIsAClearError) {
  try {
    (void)import_osm("/nonexistent/dir/city.osm.pbf");
    FAIL() << "expected MapLoadError";
  } catch (const MapLoadError& e) {
    EXPECT_NE(std::string(e.what()).find("not found"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("/nonexistent/dir/city.osm.pbf"), std::string::npos) << e.what();
  }
}

TEST(OsmImport, CorruptPbfIsAClearError) {
  TempDir dir;
  const auto file = dir.path() / "broken.osm.pbf";
  // A plausible blob-header length prefix followed by junk.
  std::string bytes("\x00\x00\x00\x0d", 4);
  bytes += "this is not a protobuf blob at all";
  std::ofstream(file, std::ios::binary) << bytes;
  try {
    OsmImportOptions options;
    options.show_progress = false;
    (void)import_osm(file, options);
    FAIL() << "expected MapLoadError";
  } catch (const MapLoadError& e) {
    EXPECT_NE(std::string(e.what()).find("broken.osm.pbf"), std::string::npos) << e.what();
  }
}

TEST(OsmImport, FileWithoutRoadsIsAClearError) {
  EXPECT_THROW((void)import_fixture({at(1, 0, 0), at(2, 100, 0)}, {{1, {1, 2}, {{"highway", "footway"}}}}),
               MapLoadError);
}

TEST(OsmImport, UnknownExtensionIsAClearError) {
  TempDir dir;
  const auto file = dir.path() / "map.txt";
  std::ofstream(file) << "hello";
  EXPECT_THROW((void)import_osm(file), MapLoadError);
}

struct ExtractCase {
  const char* file;
  std::size_t min_nodes;
};

class SharedExtract : public ::testing::TestWithParam<ExtractCase> {};

TEST_P(SharedExtract, ImportsIntoAConsistentGraph) {
  const auto file = testing::shared_osm(GetParam().file);
  if (!std::filesystem::exists(file)) GTEST_SKIP() << "shared data not present: " << file;
  OsmImportReport report;
  OsmImportOptions options;
  options.show_progress = false;
  const RoadGraph g = import_osm(file, options, &report);
  EXPECT_GE(g.node_count(), GetParam().min_nodes);
  EXPECT_GT(g.edge_count(), g.node_count());
  EXPECT_EQ(report.graph.kept_nodes + report.graph.dropped_nodes, report.graph.input_nodes);
  EXPECT_GT(report.osm_ways_kept, 0u);
  for (EdgeId e : g.edges()) {
    ASSERT_GT(g.length_m(e), 0.0);
    ASSERT_GT(g.speed_mps(e), 0.0);
    const auto pts = g.geometry(e);
    // The polyline runs from the tail node to the head node.
    ASSERT_NEAR(distance_m(pts.front(), g.position(g.tail(e))), 0.0, 1e-6);
    ASSERT_NEAR(distance_m(pts.back(), g.position(g.head(e))), 0.0, 1e-6);
    if (g.twin(e).valid()) {
      ASSERT_EQ(g.twin(g.twin(e)), e);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(AllExtracts, SharedExtract,
                         // The Berlin clip cuts the one-way carriageways at its border: only the Großer
                         // Stern roundabout itself is strongly connected.
                         ::testing::Values(ExtractCase{"monaco.osm.gz", 500}, ExtractCase{"andorra.osm.pbf", 1000},
                                           ExtractCase{"liechtenstein.osm.pbf", 3000},
                                           ExtractCase{"berlin-siegessaeule.osm.gz", 10}));

}  // namespace
}  // namespace corridor::maps

namespace corridor::maps {
namespace {

std::size_t out_degree(const RoadGraph& g, NodeId v) {
  std::size_t n = 0;
  for (EdgeId e : g.out_edges(v)) n += e.valid() ? 1 : 0;
  return n;
}

std::vector<NodeId> nodes_by_osm(const RoadGraph& g, long long osm) {
  std::vector<NodeId> out;
  for (NodeId v : g.nodes()) {
    if (g.osm_node(v).v == osm) out.push_back(v);
  }
  return out;
}

// True when the 200 m street from 1 to 3 can be driven (the detour around it is 400 m): as one
// edge, or as two through a barrier node the vehicle stops at.
bool street_passes(const RoadGraph& g) {
  for (NodeId a : nodes_by_osm(g, 1)) {
    for (EdgeId out : g.out_edges(a)) {
      if (g.osm_node(g.head(out)).v == 3 && g.length_m(out) < 250.0) return true;
      if (!g.stop_at(g.head(out))) continue;
      for (EdgeId on : g.out_edges(g.head(out))) {
        if (g.osm_node(g.head(on)).v == 3 && g.length_m(out) + g.length_m(on) < 250.0) return true;
      }
    }
  }
  return false;
}

// A street 1-2-3 with node 2 tagged `barrier_tags`, and a detour 3-4-5-1 around it.
RoadGraph street_with_node(std::map<std::string, std::string> barrier_tags, OsmImportReport* report = nullptr) {
  return import_fixture({at(1, 0, 0), at(2, 100, 0, std::move(barrier_tags)), at(3, 200, 0), at(4, 200, 100),
                         at(5, 0, 100)},
                        {{60, {1, 2, 3}, kResidential}, {61, {3, 4, 5, 1}, kResidential}}, report);
}

TEST(OsmImport, BlockingBarrierSplitsTheStreetIntoTwoDeadEnds) {
  OsmImportReport report;
  const auto g = street_with_node({{"barrier", "bollard"}}, &report);
  EXPECT_EQ(report.osm_barrier_nodes, 1u);
  const auto copies = nodes_by_osm(g, 2);
  ASSERT_EQ(copies.size(), 2u);  // one dead end on each side
  std::vector<long long> reached;
  for (NodeId b : copies) {
    ASSERT_EQ(out_degree(g, b), 1u);
    ASSERT_EQ(g.in_edges(b).size(), 1u);
    const EdgeId out = *g.out_edges(b).begin();
    reached.push_back(g.osm_node(g.head(out)).v);
    EXPECT_NEAR(g.length_m(out), 100.0, 1.0);  // each side is drivable up to the bollard
  }
  std::sort(reached.begin(), reached.end());
  EXPECT_EQ(reached, (std::vector<long long>{1, 3}));
  EXPECT_FALSE(street_passes(g));
}

// Passable nodes stay inside the chain, except those the vehicle stops at: a node of their own,
// not split.
TEST(OsmImport, PassableNodesLetTheStreetThrough) {
  for (const auto& [tags, stops] : std::vector<std::pair<std::map<std::string, std::string>, bool>>{
           {{{"barrier", "bollard"}, {"bollard", "rising"}}, true},
           {{{"barrier", "gate"}}, true},
           {{{"barrier", "lift_gate"}, {"access", "private"}}, true},
           {{{"barrier", "block"}, {"emergency", "yes"}}, true},
           {{{"access", "no"}, {"emergency", "yes"}}, false},
           {{{"barrier", "gate"}, {"access", "yes"}}, false},
           {{{"barrier", "height_restrictor"}, {"maxheight", "4.2"}}, false},
           {{{"barrier", "kerb"}, {"kerb", "lowered"}}, false}}) {
    const auto g = street_with_node(tags);
    const auto kept = nodes_by_osm(g, 2);
    EXPECT_EQ(kept.size(), stops ? 1u : 0u) << tags.begin()->first << "=" << tags.begin()->second;
    for (NodeId v : kept) EXPECT_TRUE(g.stop_at(v));
    EXPECT_TRUE(street_passes(g));
  }
}

// A barrier the vehicle stops at becomes a graph node of its own, flagged, where the street
// still passes (unlike a blocking one, which splits it into two dead ends).
TEST(OsmImport, BarriersTheVehicleStopsAtAreNodesOfTheirOwn) {
  OsmImportReport report;
  const auto g = street_with_node({{"barrier", "gate"}}, &report);
  EXPECT_EQ(report.osm_stop_nodes, 1u);
  const auto gate = nodes_by_osm(g, 2);
  ASSERT_EQ(gate.size(), 1u);
  EXPECT_TRUE(g.stop_at(gate.front()));
  EXPECT_EQ(out_degree(g, gate.front()), 2u);  // both ways along the street
  EXPECT_TRUE(street_passes(g));
  std::size_t flagged = 0;
  for (NodeId v : g.nodes()) flagged += g.stop_at(v) ? 1 : 0;
  EXPECT_EQ(flagged, 1u);
  const auto none = street_with_node({{"barrier", "cattle_grid"}});
  EXPECT_FALSE(none.has_stops());
  EXPECT_TRUE(nodes_by_osm(none, 2).empty());  // geometry inside the street, as before
}

// A gate is a graph node but no junction: a signal 10 m past it and 30 m from the junction behind
// it marks the junction, not the gate.
TEST(OsmImport, ASignalNearAGateMarksTheJunctionNotTheGate) {
  const auto g = import_fixture({at(1, 0, 0), at(2, 20, 0, {{"barrier", "gate"}}), at(3, 30, 0, {{"highway", "traffic_signals"}}),
                                 at(4, 100, 0), at(5, 100, 100), at(6, 0, 100)},
                                {{60, {1, 2, 3, 4}, kResidential}, {61, {4, 5, 6, 1}, kResidential}});
  ASSERT_EQ(nodes_by_osm(g, 2).size(), 1u);
  EXPECT_FALSE(g.signalized(nodes_by_osm(g, 2).front()));
  ASSERT_EQ(nodes_by_osm(g, 1).size(), 1u);
  EXPECT_TRUE(g.signalized(nodes_by_osm(g, 1).front()));
  EXPECT_FALSE(g.signalized(nodes_by_osm(g, 4).front()));
}

TEST(OsmImport, BlockingNodeForms) {
  for (const auto& tags : std::vector<std::map<std::string, std::string>>{
           {{"barrier", "wall"}},
           {{"barrier", "fence"}},
           {{"barrier", "kerb"}},
           {{"barrier", "gate"}, {"access", "no"}},
           {{"access", "no"}},
           {{"motor_vehicle", "no"}},
           {{"barrier", "something_new"}}}) {
    const auto g = street_with_node(tags);
    EXPECT_EQ(nodes_by_osm(g, 2).size(), 2u) << tags.begin()->first << "=" << tags.begin()->second;
    EXPECT_FALSE(street_passes(g));
  }
}

// A height restrictor is not a barrier for every vehicle: the roads through it carry its maxheight,
// and the vehicle profile decides (a 2.9 m ambulance passes 3.2 m, a 3.5 m fire engine does not).
TEST(OsmImport, HeightRestrictorBecomesALimitOnItsRoads) {
  const auto g = street_with_node({{"barrier", "height_restrictor"}, {"maxheight", "3.2"}});
  EXPECT_TRUE(nodes_by_osm(g, 2).empty());
  EXPECT_TRUE(street_passes(g));
  const EdgeId ab = edge_between(g, 1, 3), ba = edge_between(g, 3, 1);
  ASSERT_TRUE(ab.valid() && ba.valid());
  std::vector<EdgeId> limited;
  for (const EdgeLimit& l : g.edge_limits()) {
    EXPECT_FLOAT_EQ(l.max_height_m, 3.2f);
    limited.push_back(l.edge);
  }
  std::sort(limited.begin(), limited.end());
  EXPECT_EQ(limited, (std::vector<EdgeId>{std::min(ab, ba), std::max(ab, ba)}));
}

TEST(OsmImport, WayLimitsAreKeptPerEdge) {
  const auto g = import_fixture({at(1, 0, 0), at(2, 100, 0), at(3, 100, 100), at(4, 0, 100)},
                                {{90, {1, 2}, {{"highway", "residential"}, {"maxweight", "7.5"}, {"maxwidth", "2.0"}}},
                                 {91, {2, 3, 4, 1}, kResidential}});
  const EdgeId e = edge_between(g, 1, 2);
  ASSERT_TRUE(e.valid());
  ASSERT_EQ(g.edge_limits().size(), 2u);
  for (const EdgeLimit& l : g.edge_limits()) {
    EXPECT_TRUE(l.edge == e || l.edge == edge_between(g, 2, 1));
    EXPECT_FLOAT_EQ(l.max_weight_t, 7.5f);
    EXPECT_FLOAT_EQ(l.max_width_m, 2.0f);
    EXPECT_EQ(l.max_height_m, 0.0f);
  }
}

TEST(OsmImport, BarrierAtAnIntersectionClosesItForEveryRoad) {
  // 1-2-3 and 4-2-5 cross at a bollard; the outer ring keeps everything connected.
  const auto g = import_fixture({at(1, 0, 100), at(2, 100, 100, {{"barrier", "bollard"}}), at(3, 200, 100),
                                 at(4, 100, 0), at(5, 100, 200), at(6, 0, 0), at(7, 200, 0), at(8, 200, 200),
                                 at(9, 0, 200)},
                                {{70, {1, 2, 3}, kResidential},
                                 {71, {4, 2, 5}, kResidential},
                                 {72, {6, 4, 7, 3, 8, 5, 9, 1, 6}, kResidential}});
  const auto copies = nodes_by_osm(g, 2);
  EXPECT_EQ(copies.size(), 4u);
  for (NodeId b : copies) EXPECT_EQ(out_degree(g, b), 1u);
}

TEST(OsmImport, ConstructionAndDirectionalAccess) {
  const auto g = import_fixture(
      {at(1, 0, 0), at(2, 100, 0), at(3, 200, 0), at(4, 200, 100), at(5, 0, 100)},
      {{80, {1, 2}, {{"highway", "residential"}, {"motor_vehicle:backward", "no"}}},
       {81, {2, 3}, {{"highway", "residential"}, {"oneway:motor_vehicle", "yes"}}},
       {82, {3, 4, 5}, kResidential},
       {83, {5, 1}, kResidential},
       {84, {2, 4}, {{"highway", "residential"}, {"construction", "yes"}}}});
  EXPECT_TRUE(edge_between(g, 1, 2).valid());
  EXPECT_FALSE(edge_between(g, 2, 1).valid());
  EXPECT_TRUE(edge_between(g, 2, 3).valid());
  EXPECT_FALSE(edge_between(g, 3, 2).valid());
  EXPECT_FALSE(edge_between(g, 2, 4).valid());
}

}  // namespace
}  // namespace corridor::maps
