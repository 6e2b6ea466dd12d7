#include "planner/travel_cost.hpp"

#include <gtest/gtest.h>

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

}  // namespace
}  // namespace corridor::planner
