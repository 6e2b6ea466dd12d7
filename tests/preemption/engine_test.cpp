#include "preemption/engine.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "maps/graph_builder.hpp"
#include "maps/intersection_geometry.hpp"
#include "maps/synthetic_grid.hpp"
#include "planner/dstar_lite.hpp"
#include "planner/one_to_one_search.hpp"
#include "preemption/safety_monitor.hpp"
#include "preemption/simulated_signal_controller.hpp"
#include "tests/preemption/engine_rig.hpp"

namespace corridor::preemption {
namespace {


TEST(PreemptionEngine, DefaultPlanHasFourLegs) {
  Rig rig;
  ASSERT_EQ(rig.plans.size(), 1u);
  EXPECT_EQ(rig.plan().movements.size(), 12u);
}

// At 0 s the program shows 4+7 (min green 5 s). A vehicle going East -> West, due at 60 s, needs a
// phase with movement 6: 2+6 serves the West approach too, so it wins over 1+6. Trans = 5 + 3 + 2
// = 10 s, margin 3 s: start at 47 s; released 8 s after arrival.
TEST(PreemptionEngine, SchedulesTheChosenPhaseAtTheComputedStart) {
  Rig rig;
  const std::vector<Crossing> route{rig.crossing(kE, kW, 60.0)};
  rig.engine.update_route(1, 1, route, 0.0);
  const auto schedule = rig.engine.schedule(1);
  ASSERT_EQ(schedule.size(), 1u);
  EXPECT_EQ(schedule[0].phase.label, "2+6");
  EXPECT_EQ(schedule[0].movement_label, "E->W");
  EXPECT_DOUBLE_EQ(schedule[0].start_s, 47.0);
  EXPECT_DOUBLE_EQ(schedule[0].arrival_s, 60.0);
  EXPECT_DOUBLE_EQ(schedule[0].release_s, 68.0);
  EXPECT_EQ(schedule[0].state, EntryState::planned);
  rig.run_until(46.9);
  EXPECT_FALSE(rig.engine.holding(rig.c));
  rig.run_until(47.0);
  EXPECT_TRUE(rig.engine.holding(rig.c));
  EXPECT_EQ(rig.engine.schedule(1)[0].state, EntryState::active);
  // The vehicle's movement is green by its arrival.
  rig.run_until(60.0);
  const std::size_t e_w = *rig.plan().movement_index(maps::Compass::east, maps::Compass::west);
  EXPECT_EQ(rig.controller.lights(rig.c)[e_w], Light::green);
  rig.engine.vehicle_passed(1, rig.c, 61.0);
  EXPECT_EQ(rig.engine.schedule(1)[0].state, EntryState::released);
  EXPECT_FALSE(rig.engine.holding(rig.c));
  rig.run_until(61.0 + 5.0 + 2 * (3.0 + 2.0));
  EXPECT_TRUE(rig.controller.running_program(rig.c));
  EXPECT_TRUE(rig.monitor.violations().empty()) << rig.monitor.violations().front();
}

// A left turn whose lane it shares with the through movement (one lane on the approach, as SUMO's
// links say): a hold that shows the left alone leaves a through car ahead of the vehicle at red, and
// the vehicle behind it. With the lane known, the hold shows both.
TEST(PreemptionEngine, AMovementThatSharesTheVehiclesLaneIsGreenWithIt) {
  // Movements: 0 N->E (left), 1 N->S, 2 S->N, 3 E->W. The left has a protected phase of its own.
  const maps::RoadGraph g = plus_junction();
  const NodeId c = g.head(edge(g, kN, kC));
  maps::SignalPlan plan;
  plan.node = c;
  plan.movements = {{maps::Compass::north, maps::Compass::east, maps::Turn::left, 0},
                    {maps::Compass::north, maps::Compass::south, maps::Turn::through, 0},
                    {maps::Compass::south, maps::Compass::north, maps::Turn::through, 0},
                    {maps::Compass::east, maps::Compass::west, maps::Turn::through, 0}};
  plan.conflict.assign(16, 0);
  for (const auto& [x, y] : std::vector<std::pair<int, int>>{{0, 2}, {0, 3}, {1, 3}, {2, 3}}) plan.conflict[x * 4 + y] = plan.conflict[y * 4 + x] = 1;
  plan.phases = {{"N-left", {1, 0, 0, 0}, 5.0}, {"NS", {0, 1, 1, 0}, 5.0}, {"EW", {0, 0, 0, 1}, 5.0}};
  plan.program = {{1, 30.0}, {0, 10.0}, {2, 30.0}};
  const auto held_phase = [&](bool lanes_known) {
    maps::SignalPlan p = plan;
    if (lanes_known) p.lane_mates = {{1}, {0}, {}, {}};
    std::unordered_map<NodeId, maps::SignalPlan> plans{{c, p}};
    SimulatedSignalController controller(plans, 0.0);
    SafetyMonitor monitor;
    monitor.watch(plans.at(c), controller.lights(c), 0.0);
    controller.set_observer([&](NodeId n, const std::vector<Light>& l, double t) { monitor.observe(n, l, t); });
    PreemptionEngine engine(g, plans, controller);
    engine.update_route(1, 1, std::vector<Crossing>{{c, edge(g, kN, kC), edge(g, kC, kE), 60.0}}, 0.0);
    const maps::Phase phase = engine.schedule(1).at(0).phase;
    for (double t = 0.0; t <= 60.0; t += 0.5) {
      controller.advance(t);
      engine.tick(t);
    }
    EXPECT_EQ(controller.lights(c)[0], Light::green);
    EXPECT_EQ(controller.lights(c)[1] == Light::green, lanes_known);
    engine.vehicle_passed(1, c, 61.0);
    for (double t = 61.0; t <= 150.0; t += 0.5) {
      controller.advance(t);
      engine.tick(t);
    }
    EXPECT_EQ(controller.mode(c), SignalMode::program);
    EXPECT_TRUE(monitor.violations().empty()) << monitor.violations().front();
    return std::pair{phase.serves(0), phase.serves(1)};
  };
  // Without lane data the protected left alone is held: a through car ahead would wait at red.
  EXPECT_EQ(held_phase(false), std::pair(true, false));
  // With the lane known, the hold shows the through movement too.
  EXPECT_EQ(held_phase(true), std::pair(true, true));
}

TEST(PreemptionEngine, ExtendsAPhaseThatAlreadyServesTheVehicle) {
  Rig rig;
  const std::vector<Crossing> route{rig.crossing(kN, kS, 30.0)};
  rig.engine.update_route(1, 1, route, 0.0);
  const auto s = rig.engine.schedule(1)[0];
  EXPECT_EQ(s.phase.label, "4+7");  // on show at 0 s and serving N->S: no transition needed
  EXPECT_DOUBLE_EQ(s.start_s, 30.0 - 3.0);
}

TEST(PreemptionEngine, VehicleThatNeverArrivesExpiresAndTheSignalRecovers) {
  Rig rig;
  const std::vector<Crossing> route{rig.crossing(kS, kN, 40.0)};
  rig.engine.update_route(7, 1, route, 0.0);
  // Planned release is arrival + 8 s; with no report since, the hold ends 15 s after that.
  for (double t = 0; t <= 40.0 + 8.0 + 15.0; t += 1.0) rig.run_until(t);
  EXPECT_TRUE(rig.engine.holding(rig.c));  // still waiting within the grace
  rig.run_until(64.0);
  EXPECT_EQ(rig.engine.schedule(7)[0].state, EntryState::expired);
  EXPECT_FALSE(rig.engine.holding(rig.c));
  const auto events = rig.engine.take_events();
  EXPECT_TRUE(std::any_of(events.begin(), events.end(), [](const PreemptionEvent& e) {
    return e.kind == "expired" && e.detail == "reason=release_time_passed";
  }));
  rig.run_until(64.0 + 5.0 + 2 * (3.0 + 2.0));
  EXPECT_TRUE(rig.controller.running_program(rig.c));
  EXPECT_TRUE(rig.monitor.violations().empty());
}

TEST(PreemptionEngine, ForgetDropsAFinishedMission) {
  Rig rig;
  const std::vector<Crossing> route{rig.crossing(kW, kE, 20.0)};
  rig.engine.update_route(4, 1, route, 0.0);
  rig.run_until(19.0);
  ASSERT_TRUE(rig.engine.holding(rig.c));
  rig.engine.forget(4, 19.5);  // releases what it still held
  EXPECT_FALSE(rig.engine.holding(rig.c));
  EXPECT_TRUE(rig.engine.schedule(4).empty());
  rig.run_until(19.5 + 5.0 + 2 * (3.0 + 2.0));
  EXPECT_TRUE(rig.monitor.violations().empty());
}

TEST(PreemptionEngine, RerouteAwayCancelsAndReleases) {
  Rig rig;
  const std::vector<Crossing> route{rig.crossing(kW, kE, 20.0)};
  rig.engine.update_route(3, 1, route, 0.0);
  rig.run_until(19.0);
  EXPECT_TRUE(rig.engine.holding(rig.c));
  rig.engine.update_route(3, 1, {}, 19.5);  // the new route avoids the junction
  EXPECT_EQ(rig.engine.schedule(3)[0].state, EntryState::cancelled);
  EXPECT_FALSE(rig.engine.holding(rig.c));
  const auto events = rig.engine.take_events();
  EXPECT_TRUE(std::any_of(events.begin(), events.end(), [](const PreemptionEvent& e) { return e.kind == "cancelled"; }));
}

TEST(PreemptionEngine, RetimesWhenTheArrivalEstimateChanges) {
  Rig rig;
  std::vector<Crossing> route{rig.crossing(kE, kW, 60.0)};
  rig.engine.update_route(1, 1, route, 0.0);
  route[0].arrival_s = 90.0;  // the vehicle got slower
  rig.engine.update_route(1, 1, route, 1.0);
  EXPECT_DOUBLE_EQ(rig.engine.schedule(1)[0].arrival_s, 90.0);
  // At 1 s, 4+7 still owes 4 s of min green: Trans = 4 + 3 + 2 = 9 s, so p = 90 − 9 − 3 = 78 s.
  EXPECT_DOUBLE_EQ(rig.engine.schedule(1)[0].start_s, 78.0);
}

// Conflicting movements: the higher priority is served first, the other right after; with equal
// priorities the earlier arrival goes first. Deterministic, and logged.
TEST(PreemptionEngine, ArbitratesConflictingVehiclesByPriorityThenArrival) {
  for (const auto& [prio_a, prio_b, winner] : {std::tuple{1, 2, 2}, std::tuple{2, 1, 1}, std::tuple{1, 1, 1}}) {
    Rig rig;
    const std::vector<Crossing> a{rig.crossing(kN, kS, 60.0)};
    const std::vector<Crossing> b{rig.crossing(kE, kW, 62.0)};
    rig.engine.update_route(1, prio_a, a, 0.0);
    rig.engine.update_route(2, prio_b, b, 0.0);
    const auto sa = rig.engine.schedule(1)[0];
    const auto sb = rig.engine.schedule(2)[0];
    const auto& win = winner == 1 ? sa : sb;
    const auto& lose = winner == 1 ? sb : sa;
    EXPECT_FALSE(win.deferred);
    EXPECT_TRUE(lose.deferred);
    EXPECT_GE(lose.start_s, win.release_s + 3.0 + 2.0);
    const auto events = rig.engine.take_events();
    EXPECT_TRUE(std::any_of(events.begin(), events.end(), [&](const PreemptionEvent& e) {
      return e.kind == "deferred" && e.mission == lose.mission;
    }));
    for (double t = 0; t < 200; t += 0.5) {
      rig.run_until(t);
      if (t == 70.0) rig.engine.vehicle_passed(win.mission, rig.c, t);
    }
    EXPECT_TRUE(rig.monitor.violations().empty());
  }
}

// A queue on the approach makes it high congestion: the whole approach gets green, and earlier by
// the queue clearance time.
TEST(PreemptionEngine, QueueOnTheApproachStartsEarlierWithTheWholeApproach) {
  Rig rig;
  rig.engine.record_counts(rig.c, maps::Compass::east, 0.0, 0.0, 0.0);
  rig.engine.record_counts(rig.c, maps::Compass::east, 10.0, 10.0, 0.0);  // 10 queued, 1 veh/s arriving
  const std::vector<Crossing> route{rig.crossing(kE, kW, 60.0)};
  rig.engine.update_route(1, 1, route, 10.0);
  const auto s = rig.engine.schedule(1)[0];
  EXPECT_EQ(s.congestion, CongestionLevel::high);
  EXPECT_EQ(s.phase.label, "1+6");
  // Red on E->W: n_q = A(60) − D(now) = (10 + 1 × 50) − 0 = 60 vehicles; t_q = 2 + 2 × 60 = 122 s,
  // so the start is as soon as possible: now.
  EXPECT_DOUBLE_EQ(s.start_s, 10.0);
  EXPECT_THROW(rig.engine.record_counts(rig.c, maps::Compass::east, 5.0, 1.0, 0.0), CountError);
}

// The schedule follows D* Lite: after congestion moves the route, intersections no longer crossed
// are cancelled, new ones are scheduled, and every arrival matches the planner's ETA.
TEST(PreemptionEngine, FollowsDStarLiteReplans) {
  maps::GridSpec spec;
  spec.rows = 9;
  spec.cols = 9;
  spec.seed = 5;
  spec.signal_fraction = 1.0;
  spec.oneway_fraction = 0.0;
  const maps::RoadGraph g = maps::make_perturbed_grid(spec);
  const auto plans = maps::default_signal_plans(g);
  SimulatedSignalController controller(plans, 0.0);
  PreemptionEngine engine(g, plans, controller);
  planner::CostOverlay overlay(g);
  const planner::TravelCost cost(g, overlay, {15.0});
  const EdgeId first{0}, last{static_cast<std::uint32_t>(g.edge_count() - 1)};
  planner::DStarLite dstar(cost, {{first, 0.0}}, {{last, g.length_m(last)}});
  dstar.replan();
  planner::Route route = dstar.route();
  auto crossings = signalized_crossings(g, route, plans, 0.0);
  ASSERT_GE(crossings.size(), 4u);
  engine.update_route(1, 1, crossings, 0.0);
  EXPECT_EQ(engine.schedule(1).size(), crossings.size());

  // Congestion on the middle of the route: D* Lite goes around it.
  std::vector<EdgeId> changed;
  for (std::size_t i = route.edges.size() / 3; i < 2 * route.edges.size() / 3; ++i) {
    overlay.set_edge(route.edges[i], {40.0, 0.0});
    changed.push_back(route.edges[i]);
  }
  dstar.edges_changed(changed);
  dstar.replan();
  const planner::Route rerouted = dstar.route();
  ASSERT_NE(rerouted.edges, route.edges);
  const double now = 2.0;
  crossings = signalized_crossings(g, rerouted, plans, now);
  engine.update_route(1, 1, crossings, now);

  std::size_t live = 0, cancelled = 0;
  for (const ScheduleEntry& e : engine.schedule(1)) {
    const bool on_route = std::any_of(crossings.begin(), crossings.end(), [&](const Crossing& c) { return c.node == e.node; });
    if (e.state == EntryState::cancelled) {
      ++cancelled;
      EXPECT_FALSE(on_route);
    } else {
      ++live;
      ASSERT_TRUE(on_route);
      const auto c = std::find_if(crossings.begin(), crossings.end(), [&](const Crossing& x) { return x.node == e.node; });
      EXPECT_DOUBLE_EQ(e.arrival_s, c->arrival_s);
      const auto i = std::find(rerouted.nodes.begin(), rerouted.nodes.end(), e.node) - rerouted.nodes.begin();
      EXPECT_DOUBLE_EQ(e.arrival_s, now + rerouted.arrival_s[static_cast<std::size_t>(i)]);  // the planner's ETA
      EXPECT_LE(e.start_s, e.arrival_s);
    }
  }
  EXPECT_EQ(live, crossings.size());
  EXPECT_GT(cancelled, 0u);
}

TEST(PreemptionEngine, OccupancyOrSpeedRatioClassifyCongestionWithoutQueueData) {
  Rig rig;
  rig.engine.record_measurement(rig.c, maps::Compass::south, 0.45, std::nullopt);
  rig.engine.record_measurement(rig.c, maps::Compass::west, std::nullopt, 0.9);
  const std::vector<Crossing> south{rig.crossing(kS, kN, 50.0)};
  const std::vector<Crossing> west{rig.crossing(kW, kE, 50.0)};
  rig.engine.update_route(1, 1, south, 0.0);
  rig.engine.update_route(2, 1, west, 0.0);
  EXPECT_EQ(rig.engine.schedule(1)[0].congestion, CongestionLevel::high);
  EXPECT_EQ(rig.engine.schedule(1)[0].phase.label, "3+8");  // the whole South approach
  EXPECT_EQ(rig.engine.schedule(2)[0].congestion, CongestionLevel::low);
  EXPECT_THROW(rig.engine.record_measurement(rig.c, maps::Compass::west, 1.5, std::nullopt), CountError);
  EXPECT_THROW(rig.engine.record_measurement(NodeId{99}, maps::Compass::west, 0.1, std::nullopt), CountError);
}

// A vehicle stuck before the junction keeps reporting, so its arrival keeps moving out: the hold
// still ends at max_hold_s, and that vehicle is never given this junction again.
TEST(PreemptionEngine, MaxHoldCannotBeRenewedByReScheduling) {
  Rig rig;
  double t = 0.0;
  for (; t <= 200.0; t += 1.0) {
    const std::vector<Crossing> route{rig.crossing(kE, kW, t + 5.0)};  // always 5 s away
    rig.engine.update_route(1, 1, route, t);
    rig.run_until(t);
    if (t > 6.0 && t < 180.0) {
      ASSERT_TRUE(rig.engine.holding(rig.c)) << t;
    }
  }
  EXPECT_FALSE(rig.engine.holding(rig.c));
  for (; t <= 260.0; t += 1.0) {
    const std::vector<Crossing> route{rig.crossing(kE, kW, t + 5.0)};
    rig.engine.update_route(1, 1, route, t);
    rig.run_until(t);
    ASSERT_FALSE(rig.engine.holding(rig.c)) << t;
  }
  EXPECT_TRUE(rig.monitor.violations().empty());
}

// A lower-priority vehicle already holding keeps the junction until the higher-priority claim's
// own start time, rather than losing it the moment that claim is scheduled.
TEST(PreemptionEngine, ActiveHoldIsKeptUntilTheHigherClaimStarts) {
  Rig rig;
  const std::vector<Crossing> low{rig.crossing(kN, kS, 12.0)};
  rig.engine.update_route(1, 1, low, 0.0);
  rig.run_until(9.0);
  ASSERT_EQ(rig.engine.schedule(1)[0].state, EntryState::active);
  const std::vector<Crossing> high{rig.crossing(kE, kW, 40.0)};  // starts at about 27 s
  rig.engine.update_route(2, 5, high, 9.5);
  rig.run_until(10.0);
  EXPECT_EQ(rig.engine.schedule(1)[0].state, EntryState::active);
  rig.engine.vehicle_passed(1, rig.c, 13.0);
  for (double t = 13.0; t <= 40.0; t += 0.5) rig.run_until(t);
  EXPECT_EQ(rig.engine.schedule(2)[0].state, EntryState::active);
  EXPECT_TRUE(rig.monitor.violations().empty());
}

TEST(PreemptionEngine, AGreenTheProgramEndsBeforeTheArrivalIsForeseen) {
  const std::size_t n_s = [] {
    Rig rig;
    return *rig.plan().movement_index(maps::Compass::north, maps::Compass::south);
  }();
  // When the program, left alone, first ends N->S's green.
  double green_ends = 0.0;
  {
    Rig rig;
    for (double t = 0.0; t < 200.0; t += 0.5) {
      rig.controller.advance(t);
      if (rig.controller.lights(rig.c)[n_s] != Light::green) {
        green_ends = t;
        break;
      }
    }
  }
  ASSERT_GT(green_ends, 10.0);
  std::vector<double> red_at_arrival;
  for (double arrival = green_ends - 8.0; arrival <= green_ends + 30.0; arrival += 1.0) {
    Rig rig;
    for (double t = 0.0; t <= arrival; t += 0.5) {
      rig.controller.advance(t);
      if (std::fmod(t, 1.0) == 0.0) rig.engine.update_route(1, 1, std::vector<Crossing>{rig.crossing(kN, kS, arrival)}, t);
      rig.engine.tick(t);
    }
    if (rig.controller.lights(rig.c)[n_s] != Light::green) red_at_arrival.push_back(arrival);
    rig.engine.vehicle_passed(1, rig.c, arrival + 1.0);
    rig.run_until(arrival + 40.0);
    EXPECT_TRUE(rig.monitor.violations().empty()) << rig.monitor.violations().front();
  }
  EXPECT_TRUE(red_at_arrival.empty()) << red_at_arrival.size() << " arrivals met a red light, the first at "
                                      << red_at_arrival.front() << " s (the program ends the green at " << green_ends << " s)";
}

// Two junctions joined under one light (SUMO's cluster_*), crossed one after the other: one hold
// serves both stop lines, is kept when the vehicle crosses the first, and ends after the second.
TEST(PreemptionEngine, ALightOverJoinedJunctionsIsHeldAcrossAllItsStopLines) {
  // W - A - B - E, with side legs north and south of A and of B, 40 m apart.
  maps::GraphBuildInput in;
  in.origin = {47.0, 9.5};
  in.node_pos = {{-300, 0}, {0, 0}, {40, 0}, {340, 0}, {0, 200}, {0, -200}, {40, 200}, {40, -200}};
  for (std::int64_t i = 0; i < 8; ++i) in.node_osm.push_back(OsmNodeId{i + 1});
  in.node_signalized = {0, 1, 1, 0, 0, 0, 0, 0};
  const std::vector<std::pair<std::uint32_t, std::uint32_t>> legs{{0, 1}, {1, 2}, {2, 3}, {4, 1}, {1, 5}, {6, 2}, {2, 7}};
  for (const auto& [a, b] : legs) {
    maps::RoadSegment seg;
    seg.from = a;
    seg.to = b;
    seg.first_point = static_cast<std::uint32_t>(in.points.size());
    in.points.push_back(in.node_pos[a]);
    in.points.push_back(in.node_pos[b]);
    seg.last_point = seg.first_point + 1;
    seg.forward_speed_mps = seg.backward_speed_mps = 14.0f;
    seg.way = OsmWayId{static_cast<std::int64_t>(a * 10 + b)};
    in.segments.push_back(seg);
  }
  const maps::RoadGraph g = maps::build_road_graph(in);
  const auto node = [&](std::int64_t osm) {
    for (std::uint32_t v = 0; v < g.node_count(); ++v) {
      if (g.osm_node(NodeId{v}).v == osm) return NodeId{v};
    }
    return NodeId{};
  };
  const auto arc = [&](std::int64_t a, std::int64_t b) { return edge(g, a, b); };
  const NodeId a = node(2), b = node(3);
  // Movements: 0 W->A->B, 1 A->B->E, 2 north->south at A, 3 north->south at B; 0 and 2 cross, as do
  // 1 and 3. No phase of the program serves 0 and 1 together.
  maps::SignalPlan plan;
  plan.node = a;
  plan.movements = {{maps::Compass::west, maps::Compass::east, maps::Turn::through, 0},
                    {maps::Compass::west, maps::Compass::east, maps::Turn::through, 0},
                    {maps::Compass::north, maps::Compass::south, maps::Turn::through, 0},
                    {maps::Compass::north, maps::Compass::south, maps::Turn::through, 0}};
  plan.conflict.assign(16, 0);
  plan.conflict[0 * 4 + 2] = plan.conflict[2 * 4 + 0] = plan.conflict[1 * 4 + 3] = plan.conflict[3 * 4 + 1] = 1;
  plan.movement_edge = {arc(2, 3), arc(3, 4), arc(2, 6), arc(3, 8)};
  plan.phases = {{"sides", {0, 0, 1, 1}, 5.0}, {"A-west", {1, 0, 0, 1}, 5.0}, {"B-west", {0, 1, 1, 0}, 5.0}};
  plan.program = {{0, 30.0}, {1, 20.0}, {2, 20.0}};
  std::unordered_map<NodeId, maps::SignalPlan> plans{{a, plan}};
  SimulatedSignalController controller(plans, 0.0);
  SafetyMonitor monitor;
  monitor.watch(plans.at(a), controller.lights(a), 0.0);
  controller.set_observer([&](NodeId n, const std::vector<Light>& l, double t) { monitor.observe(n, l, t); });
  PreemptionEngine engine(g, plans, controller);
  engine.set_signal_nodes({{b, a}});
  // The two crossings as the caller gives them: both keyed by the light's node.
  const auto crossings = [&](double first_s) {
    return std::vector<Crossing>{{a, arc(1, 2), arc(2, 3), first_s, 300.0}, {a, arc(2, 3), arc(3, 4), first_s + 3.0, 340.0}};
  };
  engine.update_route(1, 1, crossings(40.0), 0.0);
  ASSERT_EQ(engine.schedule(1).size(), 1u);
  EXPECT_EQ(engine.schedule(1)[0].lines.size(), 2u);
  EXPECT_TRUE(engine.schedule(1)[0].phase.serves(0) && engine.schedule(1)[0].phase.serves(1)) << engine.schedule(1)[0].phase.label;
  for (double t = 0.0; t <= 40.0; t += 0.5) {
    controller.advance(t);
    engine.tick(t);
  }
  EXPECT_EQ(controller.lights(a)[0], Light::green);
  EXPECT_EQ(controller.lights(a)[1], Light::green);
  engine.vehicle_passed(1, a, 40.5);  // the first stop line
  engine.update_route(1, 1, std::vector<Crossing>{{a, arc(2, 3), arc(3, 4), 43.0, 40.0}}, 40.5);
  for (double t = 40.5; t <= 43.0; t += 0.5) {
    controller.advance(t);
    engine.tick(t);
  }
  EXPECT_TRUE(engine.holding(a));
  EXPECT_EQ(controller.lights(a)[1], Light::green);
  for (const auto& e : engine.take_events()) EXPECT_NE(e.kind, "released") << "released at " << e.time_s << " s, before the second line";
  engine.vehicle_passed(1, a, 43.5);  // the second
  EXPECT_EQ(engine.schedule(1)[0].state, EntryState::released);
  EXPECT_FALSE(engine.holding(a));
  for (double t = 43.5; t <= 120.0; t += 0.5) controller.advance(t);
  EXPECT_TRUE(monitor.violations().empty()) << monitor.violations().front();
}

TEST(PreemptionEngine, RandomMissionsNeverBreakSafetyAndSignalsRecover) {
  for (std::uint64_t seed = 1; seed <= 12; ++seed) {
    maps::GridSpec spec;
    spec.rows = 7;
    spec.cols = 7;
    spec.seed = seed;
    spec.signal_fraction = 0.6;
    const maps::RoadGraph g = maps::make_perturbed_grid(spec);
    const auto plans = maps::default_signal_plans(g);
    SimulatedSignalController controller(plans, 0.0);
    SafetyMonitor monitor;
    for (const auto& [node, plan] : plans) monitor.watch(plan, controller.lights(node), 0.0);
    controller.set_observer([&](NodeId n, const std::vector<Light>& l, double t) { monitor.observe(n, l, t); });
    // Odd seeds with the vicinity rules and random standing queues, which start holds earlier.
    PreemptionConfig config;
    config.vicinity.enabled = seed % 2 == 1;
    PreemptionEngine engine(g, plans, controller, config);
    planner::CostOverlay overlay(g);
    const planner::TravelCost cost(g, overlay, {15.0});
    planner::OneToOneSearch search;
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    auto random_route = [&](double now) {
      const EdgeId a{static_cast<std::uint32_t>(rng() % g.edge_count())};
      const EdgeId b{static_cast<std::uint32_t>(rng() % g.edge_count())};
      const auto r = search.run(planner::SearchSpace(cost, {{a, 0.0}}, {{b, g.length_m(b)}}), true);
      auto crossings = signalized_crossings(g, r, plans, now);
      for (auto& c : crossings) c.arrival_s += unit(rng) * 20.0 - 10.0;  // imperfect predictions
      return crossings;
    };
    std::map<MissionId, std::vector<Crossing>> live;
    double t = 0.0;
    MissionId next_id = 1;
    for (int step = 0; step < 400; ++step) {
      t += unit(rng) * 4.0;
      controller.advance(t);
      const double r = unit(rng);
      if (r < 0.15 || live.empty()) {
        const MissionId id = next_id++;
        live[id] = random_route(t);
        engine.update_route(id, static_cast<int>(rng() % 3), live[id], t);
      } else if (r < 0.3) {
        auto it = std::next(live.begin(), static_cast<long>(rng() % live.size()));
        it->second = random_route(t);
        engine.update_route(it->first, 1, it->second, t);
      } else if (r < 0.35) {
        auto it = std::next(live.begin(), static_cast<long>(rng() % live.size()));
        engine.cancel(it->first, t);
        live.erase(it);
      } else if (r < 0.5) {
        const auto it = std::next(plans.begin(), static_cast<long>(rng() % plans.size()));
        engine.record_queue_length(it->first, static_cast<maps::Compass>(rng() % 4), unit(rng) * 250.0);
      }
      // Vehicles pass the junctions they are due at, except a few that never show up.
      for (auto& [id, crossings] : live) {
        for (const Crossing& c : crossings) {
          if (c.arrival_s <= t && c.arrival_s > t - 4.0 && unit(rng) < 0.8) engine.vehicle_passed(id, c.node, t);
        }
      }
      engine.tick(t);
    }
    // No new missions: after the longest overrun everything has expired or been released.
    const double end = t + 60.0 + 180.0 + 40.0;
    for (double u = t; u <= end; u += 1.0) {
      controller.advance(u);
      engine.tick(u);
    }
    // Back in the normal program: never held again, and every junction shows a program phase
    // within one clearance plus one cycle.
    double horizon = 0.0;
    for (const auto& [node, plan] : plans) {
      EXPECT_FALSE(engine.holding(node)) << "seed " << seed;
      EXPECT_EQ(controller.mode(node), SignalMode::program) << "seed " << seed;
      horizon = std::max(horizon, 10.0 + 2 * (plan.yellow_s + plan.all_red_s) + plan.cycle_s());
    }
    std::unordered_map<NodeId, bool> program_phase_shown;
    for (double u = end; u <= end + horizon; u += 0.5) {
      controller.advance(u);
      for (const auto& [node, plan] : plans) program_phase_shown[node] |= controller.running_program(node);
    }
    for (const auto& [node, shown] : program_phase_shown) EXPECT_TRUE(shown) << "seed " << seed << " node " << node.v;
    ASSERT_TRUE(monitor.violations().empty()) << "seed " << seed << ": " << monitor.violations().front();
    EXPECT_GT(monitor.changes_observed(), 100u);
  }
}

}  // namespace
}  // namespace corridor::preemption
