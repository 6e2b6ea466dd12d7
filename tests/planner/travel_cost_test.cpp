#include "planner/travel_cost.hpp"

#include <gtest/gtest.h>

#include "planner/one_to_one_search.hpp"
#include "planner/search_space.hpp"
#include "tests/planner/test_graphs.hpp"
#include "tests/planner/test_graphs_line.hpp"

namespace corridor::planner {
namespace {

using testing::diamond;
using testing::edge_from_to;

TEST(TravelCost, RunningTimeUsesTheSlowerOfEdgeSpeedAndVehicleMax) {
  const auto g = diamond();
  const CostOverlay overlay(g);
  const EdgeId ab = edge_from_to(g, 1, 2);
  EXPECT_DOUBLE_EQ(TravelCost(g, overlay, {30.0}).running_time_s(ab), 10.0);  // 100 m at 10 m/s
  EXPECT_DOUBLE_EQ(TravelCost(g, overlay, {5.0}).running_time_s(ab), 20.0);   // vehicle slower than the road
}

TEST(TravelCost, CongestionFactorAndQueueDelay) {
  const auto g = diamond();
  CostOverlay overlay(g);
  const EdgeId ab = edge_from_to(g, 1, 2);
  overlay.set_edge(ab, {2.5, 12.0});
  const TravelCost cost(g, overlay, {30.0});
  EXPECT_DOUBLE_EQ(cost.running_time_s(ab), 25.0);
  EXPECT_DOUBLE_EQ(cost.edge_time_s(ab), 37.0);
}

TEST(TravelCost, FactorBelowOneNeverBeatsFreeFlow) {
  const auto g = diamond();
  CostOverlay overlay(g);
  const EdgeId ab = edge_from_to(g, 1, 2);
  overlay.set_edge(ab, {0.1, 0.0});
  // 100 m: at the edge's legal speed when the vehicle may go faster, at vmax when it may not.
  EXPECT_DOUBLE_EQ(TravelCost(g, overlay, {50.0}).running_time_s(ab), 100.0 / g.speed_mps(ab));
  EXPECT_DOUBLE_EQ(TravelCost(g, overlay, {5.0}).running_time_s(ab), 20.0);
}

TEST(TravelCost, ClosedEdgeIsInfinite) {
  const auto g = diamond();
  CostOverlay overlay(g);
  const EdgeId ab = edge_from_to(g, 1, 2);
  overlay.close_edge(ab);
  const TravelCost cost(g, overlay, {30.0});
  EXPECT_EQ(cost.edge_time_s(ab), kInfCost);
  EXPECT_EQ(cost.partial_time_s(ab, 10.0, 20.0), kInfCost);
  EXPECT_EQ(cost.partial_time_s(ab, 40.0, 40.0), 0.0);  // no distance left: already there
}

TEST(TravelCost, PartialTimeSpreadsQueueDelayAlongTheEdge) {
  const auto g = diamond();
  CostOverlay overlay(g);
  const EdgeId ab = edge_from_to(g, 1, 2);
  overlay.set_edge(ab, {1.0, 30.0});
  const TravelCost cost(g, overlay, {30.0});
  EXPECT_DOUBLE_EQ(cost.partial_time_s(ab, 20.0, 70.0), 0.5 * 40.0);
  EXPECT_DOUBLE_EQ(cost.partial_time_s(ab, 20.0, 100.0), 0.8 * 40.0);
  EXPECT_DOUBLE_EQ(cost.partial_time_s(ab, 0.0, 100.0), cost.edge_time_s(ab));
  EXPECT_DOUBLE_EQ(cost.partial_time_s(ab, 100.0, 100.0), 0.0);  // at the stop line: through the queue
}

TEST(TravelCost, TransitAddsTheTailIntersectionDelay) {
  const auto g = diamond();
  CostOverlay overlay(g);
  overlay.set_signal_delay(g, 9.0);  // B is signalized
  const TravelCost cost(g, overlay, {30.0});
  EXPECT_DOUBLE_EQ(cost.transit_s(edge_from_to(g, 2, 3)), 9.0 + 10.0);
  EXPECT_DOUBLE_EQ(cost.transit_s(edge_from_to(g, 1, 2)), 10.0);
}

TEST(TravelCost, LowerBoundNeverExceedsAnEdgesCost) {
  const auto g = diamond();
  CostOverlay overlay(g);
  overlay.set_edge(edge_from_to(g, 1, 2), {0.2, 0.0});  // "faster than free flow" must not break it
  for (const double vmax : {5.0, 25.0, 80.0}) {
    const TravelCost cost(g, overlay, {vmax});
    for (EdgeId e : g.edges()) {
      EXPECT_LE(cost.lower_bound_s(g.tail(e), g.head(e)), cost.transit_s(e));
    }
  }
}

TEST(CostOverlay, RejectsInvalidUpdatesWithClearMessages) {
  const auto g = diamond();
  CostOverlay overlay(g);
  EXPECT_THROW(overlay.set_edge(EdgeId{999}, {}), CostUpdateError);
  EXPECT_THROW(overlay.set_edge(kInvalidEdge, {}), CostUpdateError);
  EXPECT_THROW(overlay.set_edge(EdgeId{0}, {0.0, 0.0}), CostUpdateError);
  EXPECT_THROW(overlay.set_edge(EdgeId{0}, {-1.0, 0.0}), CostUpdateError);
  EXPECT_THROW(overlay.set_edge(EdgeId{0}, {std::nan(""), 0.0}), CostUpdateError);
  EXPECT_THROW(overlay.set_edge(EdgeId{0}, {1.0, -3.0}), CostUpdateError);
  EXPECT_THROW(overlay.set_edge(EdgeId{0}, {1.0, kInfCost}), CostUpdateError);
  EXPECT_THROW(overlay.set_node_delay(NodeId{99}, 1.0), CostUpdateError);
  EXPECT_THROW(overlay.set_node_delay(NodeId{0}, std::nan("")), CostUpdateError);
  EXPECT_EQ(overlay.edge(EdgeId{0}), EdgeCondition{});  // nothing was changed by the rejected calls
  EXPECT_THROW(TravelCost(g, overlay, {0.0}), CostUpdateError);
  EXPECT_THROW(TravelCost(g, overlay, {-5.0}), CostUpdateError);
}

// A movement's delay belongs to one (in, out) pair at one node, and nothing else.
TEST(CostOverlay, TurnDelayBelongsToOneMovement) {
  const auto g = testing::random_grid(3, 5, 5);
  CostOverlay overlay(g);
  EXPECT_FALSE(overlay.has_turn_delays());
  NodeId n;
  for (NodeId v : g.nodes()) {
    if (g.in_edges(v).size() >= 2 && g.out_edges(v).size() >= 2) n = v;
  }
  ASSERT_TRUE(n.valid());
  const EdgeId in0 = g.in_edges(n)[0], in1 = g.in_edges(n)[1];
  const EdgeId out0 = *g.out_edges(n).begin();
  const EdgeId out1{out0.v + 1};
  overlay.set_turn_delay(in0, out1, 7.5);
  EXPECT_TRUE(overlay.has_turn_delays());
  EXPECT_DOUBLE_EQ(overlay.turn_delay_s(in0, out1), 7.5);
  EXPECT_DOUBLE_EQ(overlay.turn_delay_s(in0, out0), 0.0);
  EXPECT_DOUBLE_EQ(overlay.turn_delay_s(in1, out1), 0.0);
  overlay.set_turn_delay(in1, out0, 2.0);
  EXPECT_DOUBLE_EQ(overlay.turn_delay_s(in1, out0), 2.0);
  EXPECT_DOUBLE_EQ(overlay.turn_delay_s(in0, out1), 7.5);
  EXPECT_DOUBLE_EQ(overlay.node_delay_s(n), 0.0);  // the node itself is untouched
}

TEST(CostOverlay, RejectsInvalidTurnDelays) {
  const auto g = testing::random_grid(3, 4, 4);
  CostOverlay overlay(g);
  EdgeId in;
  for (EdgeId e : g.edges()) {
    if (!in.valid() && !g.out_edges(g.head(e)).empty()) in = e;
  }
  ASSERT_TRUE(in.valid());
  const EdgeId out = *g.out_edges(g.head(in)).begin();
  ASSERT_EQ(g.tail(out), g.head(in));  // so the value checks below fail on the value, not the pair
  overlay.set_turn_delay(in, out, 0.0);  // and the pair itself is accepted
  EdgeId elsewhere = out;
  for (EdgeId e : g.edges()) {
    if (g.tail(e) != g.head(in)) elsewhere = e;
  }
  EXPECT_THROW(overlay.set_turn_delay(EdgeId{99999}, out, 1.0), CostUpdateError);
  EXPECT_THROW(overlay.set_turn_delay(in, kInvalidEdge, 1.0), CostUpdateError);
  EXPECT_THROW(overlay.set_turn_delay(in, elsewhere, 1.0), CostUpdateError);  // the edges do not meet
  EXPECT_THROW(overlay.set_turn_delay(in, out, -1.0), CostUpdateError);
  EXPECT_THROW(overlay.set_turn_delay(in, out, std::nan("")), CostUpdateError);
  EXPECT_THROW(overlay.set_turn_delay(in, out, kInfCost), CostUpdateError);
  EXPECT_DOUBLE_EQ(overlay.turn_delay_s(in, out), 0.0);  // nothing was stored by the rejected calls
}

// A long wait on the one movement a route makes at a junction moves the route off that movement,
// and the route's time is what the search charged, the movement's delay included.
TEST(TravelCost, AMovementDelaySteersTheRouteAndIsCharged) {
  maps::GridSpec spec;  // two-way streets throughout, so every block has a way round it
  spec.rows = spec.cols = 6;
  spec.removal_fraction = spec.oneway_fraction = spec.diagonal_fraction = 0.0;
  const auto g = maps::make_perturbed_grid(spec);
  CostOverlay overlay(g);
  const TravelCost cost(g, overlay, {30.0});
  OneToOneSearch search;
  const std::vector<EdgePoint> from{{EdgeId{0}, 0.0}};
  const std::vector<EdgePoint> to{{EdgeId{static_cast<std::uint32_t>(g.edge_count() - 1)}, 0.0}};
  const Route before = search.run(SearchSpace(cost, from, to), false);
  ASSERT_TRUE(before.found);
  ASSERT_GE(before.edges.size(), 5u);
  // A movement mid-route, where the grid offers ways round it.
  const std::size_t mid = before.edges.size() / 2;
  const EdgeId in = before.edges[mid - 1], out = before.edges[mid];
  // A small delay on the route's movement is simply paid.
  overlay.set_turn_delay(in, out, 0.25);
  const Route small = search.run(SearchSpace(cost, from, to), false);
  EXPECT_EQ(small.edges, before.edges);
  EXPECT_NEAR(small.travel_time_s, before.travel_time_s + 0.25, 1e-9);
  // A long one is driven around, for less than it would cost.
  overlay.set_turn_delay(in, out, 1000.0);
  const Route after = search.run(SearchSpace(cost, from, to), false);
  ASSERT_TRUE(after.found);
  for (std::size_t i = 1; i < after.edges.size(); ++i) {
    EXPECT_FALSE(after.edges[i - 1] == in && after.edges[i] == out);
  }
  EXPECT_GE(after.travel_time_s, before.travel_time_s);
  EXPECT_LT(after.travel_time_s, before.travel_time_s + 1000.0);
}

}  // namespace
}  // namespace corridor::planner
