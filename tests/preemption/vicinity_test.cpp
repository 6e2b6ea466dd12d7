// The engine's vicinity rules on three signalized junctions in a row: queues on the approach, a
// link about to spill back, side links, and the bound on an early start.
#include <gtest/gtest.h>

#include <algorithm>
#include <memory>

#include "preemption/engine.hpp"
#include "tests/preemption/engine_rig.hpp"

namespace corridor::preemption {
namespace {

// Three signalized junctions in a row, A (x = 0), B (x = 200 m) and D (x = 400 m), each with side
// legs 200 m north and south, and 200 m of road before A and after D.
struct CorridorRig {
  maps::RoadGraph graph = [] {
    maps::GraphBuildInput in;
    in.origin = {47.0, 9.5};
    // 0 west end, 1 A, 2 B, 3 D, 4 east end, then north and south of A, B, D.
    in.node_pos = {{-200, 0}, {0, 0}, {200, 0}, {400, 0}, {600, 0}, {0, 200}, {0, -200}, {200, 200}, {200, -200}, {400, 200}, {400, -200}};
    for (std::int64_t i = 0; i < static_cast<std::int64_t>(in.node_pos.size()); ++i) in.node_osm.push_back(OsmNodeId{i + 1});
    in.node_signalized = {0, 1, 1, 1, 0, 0, 0, 0, 0, 0, 0};
    const std::vector<std::pair<std::uint32_t, std::uint32_t>> roads{{0, 1}, {1, 2}, {2, 3}, {3, 4}, {1, 5}, {1, 6}, {2, 7}, {2, 8}, {3, 9}, {3, 10}};
    for (const auto& [from, to] : roads) {
      maps::RoadSegment s;
      s.from = from;
      s.to = to;
      s.first_point = static_cast<std::uint32_t>(in.points.size());
      in.points.push_back(in.node_pos[from]);
      in.points.push_back(in.node_pos[to]);
      s.last_point = s.first_point + 1;
      s.forward_speed_mps = s.backward_speed_mps = 10.0f;
      s.way = OsmWayId{static_cast<std::int64_t>(in.segments.size() + 1)};
      in.segments.push_back(s);
    }
    return maps::build_road_graph(in);
  }();
  std::unordered_map<NodeId, maps::SignalPlan> plans = maps::default_signal_plans(graph);
  SimulatedSignalController controller{plans, 0.0};
  SafetyMonitor monitor;
  std::unique_ptr<PreemptionEngine> engine;
  NodeId a = node(2), b = node(3), d = node(4);

  explicit CorridorRig(bool vicinity) {
    PreemptionConfig config;
    config.vicinity.enabled = vicinity;
    engine = std::make_unique<PreemptionEngine>(graph, plans, controller, config);
    for (const auto& [n, plan] : plans) monitor.watch(plan, controller.lights(n), 0.0);
    controller.set_observer([this](NodeId n, const std::vector<Light>& l, double t) { monitor.observe(n, l, t); });
  }
  NodeId node(std::int64_t osm) const {
    for (std::uint32_t v = 0; v < graph.node_count(); ++v) {
      if (graph.osm_node(NodeId{v}).v == osm) return NodeId{v};
    }
    return NodeId{};
  }
  // The vehicle 100 m before A, eastwards through A, B and D at 4 m/s (slowed by traffic).
  std::vector<Crossing> eastwards(double now_s) const {
    planner::Route r;
    r.found = true;
    r.start = {edge(graph, 1, 2), 100.0};
    r.edges = {edge(graph, 1, 2), edge(graph, 2, 3), edge(graph, 3, 4), edge(graph, 4, 5)};
    r.nodes = {a, b, d, node(5)};
    r.arrival_s = {30.0, 80.0, 130.0, 180.0};
    return signalized_crossings(graph, r, plans, now_s);
  }
  ScheduleEntry at(NodeId n) const {
    const auto schedule = engine->schedule(1);
    const auto it = std::find_if(schedule.begin(), schedule.end(), [&](const ScheduleEntry& e) { return e.node == n; });
    return it != schedule.end() ? *it : ScheduleEntry{};
  }
};

TEST(VicinityPreemption, CrossingsCarryTheirDistanceAlongTheRoute) {
  const CorridorRig rig(true);
  const auto crossings = rig.eastwards(0.0);
  ASSERT_EQ(crossings.size(), 3u);
  EXPECT_NEAR(crossings[0].distance_m, 100.0, 1.0);
  EXPECT_NEAR(crossings[1].distance_m, 300.0, 1.0);
  EXPECT_NEAR(crossings[2].distance_m, 500.0, 1.0);
}

// Without a measured queue the vicinity rules change nothing: the same schedule as route-only.
TEST(VicinityPreemption, WithoutQueuesTheScheduleIsRouteOnly) {
  CorridorRig with(true), without(false);
  with.engine->update_route(1, 1, with.eastwards(0.0), 0.0);
  without.engine->update_route(1, 1, without.eastwards(0.0), 0.0);
  for (NodeId n : {with.a, with.b, with.d}) {
    EXPECT_DOUBLE_EQ(with.at(n).start_s, without.at(n).start_s);
    EXPECT_TRUE(with.at(n).vicinity.empty());
  }
}

// Upstream approach: 60 m of standing queue (8 vehicles) before B. The vehicle meets its tail 15 s
// before the stop line, and the queue needs t_q = 2 + 2 × 8 = 18 s to move, so the hold starts at
// τ − 15 − Trans − margin − 18 instead of τ − Trans − margin. Route-only ignores it (the queue is no
// count the estimator has, and the approach is not classified as congested).
TEST(VicinityPreemption, ApproachQueueStartsClearanceBeforeTheVehicleMeetsItsTail) {
  CorridorRig with(true), without(false);
  const auto west = maps::approach_side(with.graph, edge(with.graph, 2, 3));
  with.engine->record_queue_length(with.b, west, 60.0);
  without.engine->record_queue_length(without.b, west, 60.0);
  with.engine->update_route(1, 1, with.eastwards(0.0), 0.0);
  without.engine->update_route(1, 1, without.eastwards(0.0), 0.0);
  const ScheduleEntry v = with.at(with.b);
  const ScheduleEntry r = without.at(without.b);
  EXPECT_EQ(v.vicinity, "approach_queue");
  EXPECT_TRUE(r.vicinity.empty());
  const double trans = transition_time_s(with.controller.remaining_min_green_s(with.b, 0.0), with.plans.at(with.b).yellow_s,
                                         with.plans.at(with.b).all_red_s);
  EXPECT_NEAR(v.start_s, 80.0 - 15.0 - trans - 3.0 - 18.0, 1e-6);
  // The queue moves whatever its vehicles' turns: the whole West approach is green.
  EXPECT_EQ(v.congestion, CongestionLevel::high);
  const maps::SignalPlan& plan = with.plans.at(with.b);
  for (std::size_t m = 0; m < plan.movements.size(); ++m) {
    if (plan.movements[m].from == west) {
      EXPECT_TRUE(v.phase.serves(m)) << plan.movements[m].label();
    }
  }
  EXPECT_EQ(r.congestion, CongestionLevel::low);
  EXPECT_LT(v.start_s, r.start_s);
  // A and D have no queue: untouched.
  EXPECT_DOUBLE_EQ(with.at(with.a).start_s, without.at(without.a).start_s);
  EXPECT_DOUBLE_EQ(with.at(with.d).start_s, without.at(without.d).start_s);
}

// Downstream link: 150 m of queue on the 200 m link A -> B is about to spill back into A. B's
// outflow must be moving when the vehicle reaches A (τ_A = 30 s): start ≤ τ_A − Trans − margin −
// t_q(20 vehicles), which is now. B gets its whole West approach (every queued turn moves), and
// the early hold is released like any other, with no safety violation.
TEST(VicinityPreemption, LinkAboutToSpillBackGetsItsOutflowGreenBeforeTheVehicleExits) {
  CorridorRig rig(true);
  const auto west = maps::approach_side(rig.graph, edge(rig.graph, 2, 3));
  rig.engine->record_queue_length(rig.b, west, 150.0);
  rig.engine->update_route(1, 1, rig.eastwards(0.0), 0.0);
  const ScheduleEntry e = rig.at(rig.b);
  EXPECT_EQ(e.vicinity, "spillback");
  EXPECT_EQ(e.congestion, CongestionLevel::high);
  EXPECT_DOUBLE_EQ(e.start_s, 0.0);
  const maps::SignalPlan& plan = rig.plans.at(rig.b);
  for (std::size_t m = 0; m < plan.movements.size(); ++m) {
    if (plan.movements[m].from == west) {
      EXPECT_TRUE(e.phase.serves(m)) << plan.movements[m].label();
    }
  }
  // A queue below the spill-back share is only an approach queue.
  CorridorRig shorter(true);
  shorter.engine->record_queue_length(shorter.b, west, 20.0);
  shorter.engine->update_route(1, 1, shorter.eastwards(0.0), 0.0);
  EXPECT_EQ(shorter.at(shorter.b).vicinity, "approach_queue");
  EXPECT_GT(shorter.at(shorter.b).start_s, 0.0);

  // The vehicle passes A, B and D; every hold ends and the signals go back to their program.
  double t = 0.0;
  for (; t <= 250.0; t += 0.5) {
    rig.controller.advance(t);
    if (t == 30.0) rig.engine->vehicle_passed(1, rig.a, t);
    if (t == 80.0) rig.engine->vehicle_passed(1, rig.b, t);
    if (t == 130.0) rig.engine->vehicle_passed(1, rig.d, t);
    rig.engine->tick(t);
  }
  for (NodeId n : {rig.a, rig.b, rig.d}) EXPECT_FALSE(rig.engine->holding(n));
  EXPECT_TRUE(rig.monitor.violations().empty()) << rig.monitor.violations().front();
}

// Side link: the vehicle turns north at B, but the link B -> D, which vehicles ahead of it in its
// lane may take, holds 150 m of queue: about to spill back into B. D's West approach (the outflow
// of that link) is flushed before the vehicle reaches B, and released when it has passed B. A
// shorter queue flushes nothing, and neither does route-only preemption.
TEST(VicinityPreemption, SideLinkAboutToSpillBackIsFlushedAndReleasedWithTheCrossing) {
  const auto north_at_b = [](const CorridorRig& rig) {
    planner::Route r;
    r.found = true;
    r.start = {edge(rig.graph, 1, 2), 100.0};
    r.edges = {edge(rig.graph, 1, 2), edge(rig.graph, 2, 3), edge(rig.graph, 3, 8)};
    r.nodes = {rig.a, rig.b, rig.node(8)};
    r.arrival_s = {30.0, 80.0, 110.0};
    return signalized_crossings(rig.graph, r, rig.plans, 0.0);
  };
  CorridorRig rig(true), off(false), shorter(true);
  const auto west = maps::approach_side(rig.graph, edge(rig.graph, 3, 4));
  rig.engine->record_queue_length(rig.d, west, 150.0);
  off.engine->record_queue_length(off.d, west, 150.0);
  shorter.engine->record_queue_length(shorter.d, west, 60.0);
  rig.engine->update_route(1, 1, north_at_b(rig), 0.0);
  off.engine->update_route(1, 1, north_at_b(off), 0.0);
  shorter.engine->update_route(1, 1, north_at_b(shorter), 0.0);
  const ScheduleEntry flush = rig.at(rig.d);
  ASSERT_TRUE(flush.flush_for.has_value());
  EXPECT_EQ(*flush.flush_for, rig.b);
  EXPECT_EQ(flush.vicinity, "side_spillback");
  const double trans =
      transition_time_s(rig.controller.remaining_min_green_s(rig.d, 0.0), rig.plans.at(rig.d).yellow_s, rig.plans.at(rig.d).all_red_s);
  EXPECT_NEAR(flush.start_s, std::max(80.0 - 90.0, 80.0 - trans - 3.0 - (2.0 + 2.0 * 20.0)), 1e-6);
  EXPECT_LE(flush.start_s, 80.0 - trans - 3.0);
  const maps::SignalPlan& plan = rig.plans.at(rig.d);
  for (std::size_t m = 0; m < plan.movements.size(); ++m) {
    if (plan.movements[m].from == west) {
      EXPECT_TRUE(flush.phase.serves(m)) << plan.movements[m].label();
    }
  }
  EXPECT_FALSE(off.at(off.d).flush_for.has_value());
  // Its events say they are about a flush, so that a caller can keep them apart from the route's.
  const auto events = rig.engine->take_events();
  EXPECT_TRUE(std::any_of(events.begin(), events.end(), [&](const PreemptionEvent& ev) { return ev.node == rig.d && ev.side_flush; }));
  EXPECT_TRUE(std::none_of(events.begin(), events.end(), [&](const PreemptionEvent& ev) { return ev.node == rig.b && ev.side_flush; }));
  EXPECT_EQ(off.engine->schedule(1).size(), 2u);
  EXPECT_EQ(shorter.engine->schedule(1).size(), 2u);

  double t = 0.0;
  for (; t <= 200.0; t += 0.5) {
    rig.controller.advance(t);
    if (t == 40.0) {
      // The flush (on since about 25 s) drained the queue: it still runs until the vehicle passes B.
      rig.engine->record_queue_length(rig.d, west, 0.0);
      rig.engine->update_route(1, 1, north_at_b(rig), t);
      EXPECT_EQ(rig.at(rig.d).state, EntryState::active);
    }
    if (t == 30.0) rig.engine->vehicle_passed(1, rig.a, t);
    if (t == 80.0) {
      EXPECT_TRUE(rig.engine->holding(rig.d));
      rig.engine->vehicle_passed(1, rig.b, t);
      EXPECT_EQ(rig.at(rig.d).state, EntryState::released);
    }
    rig.engine->tick(t);
  }
  for (NodeId n : {rig.a, rig.b, rig.d}) EXPECT_FALSE(rig.engine->holding(n));
  EXPECT_TRUE(rig.monitor.violations().empty()) << rig.monitor.violations().front();
}

// No vicinity rule starts a hold more than max_lead_s before the arrival, however long the queue.
TEST(VicinityPreemption, EarlyStartIsBoundedByTheMaximumLead) {
  CorridorRig rig(true);
  planner::Route r;
  r.found = true;
  r.start = {edge(rig.graph, 1, 2), 0.0};
  r.edges = {edge(rig.graph, 1, 2), edge(rig.graph, 2, 3), edge(rig.graph, 3, 4)};
  r.nodes = {rig.a, rig.b, rig.d};
  r.arrival_s = {100.0, 200.0, 300.0};  // a slow vehicle
  const auto west = maps::approach_side(rig.graph, edge(rig.graph, 2, 3));
  rig.engine->record_queue_length(rig.b, west, 190.0);
  rig.engine->update_route(1, 1, signalized_crossings(rig.graph, r, rig.plans, 0.0), 0.0);
  EXPECT_DOUBLE_EQ(rig.at(rig.b).start_s, 200.0 - 90.0);
  EXPECT_THROW(rig.engine->record_queue_length(rig.b, west, -1.0), CountError);
  EXPECT_THROW(rig.engine->record_queue_length(rig.b, west, std::nan("")), CountError);
  EXPECT_THROW(rig.engine->record_queue_length(rig.node(1), west, 10.0), CountError);
}

// Property test: many random missions with planner routes over a grid of signalized junctions,
// random arrivals (some vehicles never come), reroutes and cancels. No safety violation ever, and
// every junction is back in its normal program within a bounded time once the missions are over.

// The program's own green for the vehicle can end just before it arrives: the start taken from what
// is on show (extend, so no Trans) would fall into the next phase's minimum green. For every
// arrival in the cycle the vehicle's movement must be green when it arrives, re-timed every second
// as a moving vehicle is.

}  // namespace
}  // namespace corridor::preemption
