#include "planner/route.hpp"

#include <gtest/gtest.h>

#include "planner/route_geojson.hpp"
#include "planner/snap_points.hpp"
#include "tests/planner/test_graphs_line.hpp"

namespace corridor::planner {
namespace {

using testing::diamond;
using testing::edge_from_to;

TEST(Route, ArrivalTimesAndCostToGoalAlongTheRoute) {
  const auto g = diamond();
  CostOverlay overlay(g);
  overlay.set_node_delay(NodeId{g.head(edge_from_to(g, 1, 4))}, 4.0);  // D
  const TravelCost cost(g, overlay, {30.0});
  const EdgeId ba = edge_from_to(g, 2, 1), ad = edge_from_to(g, 1, 4), dc = edge_from_to(g, 4, 3);
  const Route r = make_route(cost, {ba, 40.0}, {ba, ad, dc}, {dc, g.length_m(dc) / 2});
  ASSERT_TRUE(r.found);
  ASSERT_EQ(r.nodes.size(), 2u);
  const double ad_s = g.length_m(ad) / 20.0;
  EXPECT_DOUBLE_EQ(r.arrival_s[0], 6.0);                 // 60 m of B->A at 10 m/s, then at A
  EXPECT_NEAR(r.arrival_s[1], 6.0 + ad_s, 1e-12);        // at D, before its 4 s delay
  EXPECT_NEAR(r.travel_time_s, 6.0 + ad_s + 4.0 + ad_s / 2, 1e-12);
  EXPECT_NEAR(*r.cost_to_goal_s(r.nodes[1]), 4.0 + ad_s / 2, 1e-12);
  EXPECT_FALSE(r.cost_to_goal_s(NodeId{g.head(edge_from_to(g, 1, 2))}).has_value());  // B is not crossed
  EXPECT_NEAR(r.length_m, 60.0 + g.length_m(ad) * 1.5, 1e-9);
}

TEST(Route, PolylineIsClippedAtStartAndGoal) {
  const auto g = diamond();
  const CostOverlay overlay(g);
  const TravelCost cost(g, overlay, {30.0});
  const EdgeId ab = edge_from_to(g, 1, 2), bc = edge_from_to(g, 2, 3);
  const Route r = make_route(cost, {ab, 25.0}, {ab, bc}, {bc, 40.0});
  const auto line = route_polyline(g, r);
  ASSERT_EQ(line.size(), 3u);  // start point, B, goal point
  EXPECT_NEAR(line.front().x_m, 25.0, 1e-9);
  EXPECT_NEAR(line[1].x_m, 100.0, 1e-9);
  EXPECT_NEAR(line.back().x_m, 140.0, 1e-9);
}

TEST(Route, GeoJsonFeatureIsLonLatWithProperties) {
  const auto g = diamond();
  CostOverlay overlay(g);
  overlay.set_signal_delay(g, 5.0);
  const TravelCost cost(g, overlay, {30.0});
  const EdgeId ab = edge_from_to(g, 1, 2), bc = edge_from_to(g, 2, 3);
  const Route r = make_route(cost, {ab, 0.0}, {ab, bc}, {bc, 100.0});
  const auto f = route_to_geojson(g, r, "astar");
  EXPECT_EQ(f["type"], "Feature");
  EXPECT_EQ(f["geometry"]["type"], "LineString");
  const auto& first = f["geometry"]["coordinates"][0];
  EXPECT_NEAR(first[0].get<double>(), 9.5, 1e-3);  // lon first
  EXPECT_NEAR(first[1].get<double>(), 47.0, 1e-3);
  EXPECT_DOUBLE_EQ(f["properties"]["travel_time_s"].get<double>(), 25.0);
  EXPECT_DOUBLE_EQ(f["properties"]["length_m"].get<double>(), 200.0);
  EXPECT_EQ(f["properties"]["algorithm"], "astar");
  EXPECT_EQ(f["properties"]["nodes"].size(), 1u);
  EXPECT_EQ(f["properties"]["signals"].size(), 1u);
}

// A coordinate exactly on node B: as a goal it is the end of A->B (no zero-length piece of B->A),
// as a start the beginning of B->A; mid-edge, both directions stay.
TEST(SnapPoints, NodeCoordinatesGiveNoZeroLengthPieces) {
  const auto g = diamond();
  const EdgeId ab = edge_from_to(g, 1, 2), ba = edge_from_to(g, 2, 1);
  maps::SnapResult at_b;
  at_b.edge = ab;
  at_b.offset_m = 100.0;
  at_b.twin = ba;
  at_b.twin_offset_m = 0.0;
  const auto goal = points_from_snap(g, at_b, PointRole::goal);
  ASSERT_EQ(goal.size(), 1u);
  EXPECT_EQ(goal[0].edge, ab);
  EXPECT_DOUBLE_EQ(goal[0].offset_m, 100.0);
  const auto start = points_from_snap(g, at_b, PointRole::start);
  ASSERT_EQ(start.size(), 1u);
  EXPECT_EQ(start[0].edge, ba);
  EXPECT_DOUBLE_EQ(start[0].offset_m, 0.0);
  maps::SnapResult mid = at_b;
  mid.offset_m = 40.0;
  mid.twin_offset_m = 60.0;
  EXPECT_EQ(points_from_snap(g, mid, PointRole::goal).size(), 2u);
  EXPECT_EQ(points_from_snap(g, mid, PointRole::start).size(), 2u);
}

}  // namespace
}  // namespace corridor::planner
