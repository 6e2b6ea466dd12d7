// The virtual NTCIP 1202 controller's logic, without a socket: a preempt call runs entry (minimum
// green, yellow, all-red), then dwell in the preempt's phase, and exits to the program when the
// call is removed, dropped by the watchdog or held past max presence; phase control serves the
// held and called phases; SETs are checked as a command responder must. A safety monitor watches
// every change for conflicting greens and skipped clearances.
#include "ntcip/virtual_intersection.hpp"

#include <gtest/gtest.h>

#include "maps/graph_builder.hpp"
#include "maps/intersection_geometry.hpp"
#include "preemption/safety_monitor.hpp"
#include "preemption/simulated_signal_controller.hpp"
#include "tests/preemption/engine_rig.hpp"

namespace corridor::ntcip {
namespace {

using preemption::plus_junction;  // legs 200 m to the N, E, S and W

struct Rig {
  maps::RoadGraph graph = plus_junction();
  std::unordered_map<NodeId, maps::SignalPlan> plans = maps::default_signal_plans(graph);
  NodeId node = plans.begin()->first;
  preemption::SimulatedSignalController controller{plans, 0.0};
  preemption::SafetyMonitor monitor;
  VirtualIntersection x{node,
                        plans.at(node),
                        {{1, maps::Compass::north, {}}, {2, maps::Compass::east, {}}, {3, maps::Compass::south, {}}, {4, maps::Compass::west, {}}},
                        controller,
                        "test",
                        VirtualTiming{20.0, 60.0}};
  double t = 0.0;

  Rig() {
    monitor.watch(plans.at(node), controller.lights(node), 0.0);
    controller.set_observer([this](NodeId n, const std::vector<preemption::Light>& l, double at) { monitor.observe(n, l, at); });
    x.step(0.0);
  }
  void run_to(double end) {
    for (; t < end; t += 0.5) {
      controller.advance(t);
      x.step(t);
    }
  }
  void set(const Oid& o, std::int64_t v) {
    ASSERT_EQ(x.check_set(o, Value{Value::Type::integer, v, {}, {}}), SetStatus::ok);
    x.set(o, Value{Value::Type::integer, v, {}, {}}, t);
  }
  std::int64_t get(const Oid& o) { return x.get(o, t)->integer; }
  // The NTCIP phases (plan movements + 1) green now, as phaseStatusGroupGreens.1 reports them.
  std::int64_t greens() { return get(column(oid::kPhaseStatusGroupGreens, 1)) | (get(column(oid::kPhaseStatusGroupGreens, 2)) << 8); }
  std::int64_t phase_bits(const maps::Phase& p) {
    std::int64_t bits = 0;
    for (std::size_t m = 0; m < p.green.size(); ++m) bits |= p.green[m] ? (1ll << m) : 0;
    return bits;
  }
  PreemptState state(std::uint32_t n) { return static_cast<PreemptState>(get(column(oid::kPreemptState, n))); }
};

TEST(VirtualIntersection, APreemptCallRunsEntryDwellAndExitBackToTheProgram) {
  Rig rig;
  EXPECT_EQ(rig.state(4), PreemptState::not_active);
  rig.run_to(3.0);
  rig.set(column(oid::kPreemptControlState, 4), 1);
  EXPECT_EQ(rig.state(4), PreemptState::entry_started);
  // Entry keeps the running phase's minimum green, then yellow and all-red: not at once.
  rig.run_to(3.5);
  EXPECT_EQ(rig.state(4), PreemptState::entry_started);
  rig.run_to(20.0);
  ASSERT_EQ(rig.state(4), PreemptState::dwell);
  EXPECT_EQ(rig.greens(), rig.phase_bits(rig.x.preempt_phase(4)));
  for (std::size_t m = 0; m < rig.plans.at(rig.node).movements.size(); ++m) {
    if (rig.plans.at(rig.node).movements[m].from == maps::Compass::west && rig.x.preempt_phase(4).serves(m)) {
      EXPECT_EQ(rig.controller.lights(rig.node)[m], preemption::Light::green);
    }
  }
  // NTCIP serves the lowest-numbered call: preempt 2 takes over, and 4 waits with its call on
  // until 2 is removed.
  rig.set(column(oid::kPreemptControlState, 2), 1);
  EXPECT_EQ(rig.state(2), PreemptState::entry_started);
  EXPECT_EQ(rig.state(4), PreemptState::not_active_with_call);
  rig.run_to(40.0);
  EXPECT_EQ(rig.state(2), PreemptState::dwell);
  rig.set(column(oid::kPreemptControlState, 4), 1);  // its sender re-asserts it, as a keep-alive
  rig.set(column(oid::kPreemptControlState, 2), 0);
  rig.run_to(55.0);
  EXPECT_EQ(rig.state(4), PreemptState::dwell);
  rig.set(column(oid::kPreemptControlState, 4), 0);
  EXPECT_EQ(rig.state(4), PreemptState::exit_started);
  rig.run_to(80.0);
  EXPECT_EQ(rig.state(4), PreemptState::not_active);
  EXPECT_TRUE(rig.controller.running_program(rig.node));
  EXPECT_TRUE(rig.monitor.violations().empty()) << rig.monitor.violations().front();
}

TEST(VirtualIntersection, ACallNotReassertedIsDroppedAndMaxPresenceEndsADwell) {
  Rig rig;
  rig.set(column(oid::kPreemptControlState, 1), 1);
  rig.run_to(15.0);
  EXPECT_EQ(rig.state(1), PreemptState::dwell);
  rig.run_to(21.0);  // 20 s without a re-assertion
  EXPECT_EQ(rig.get(column(oid::kPreemptControlState, 1)), 0);
  EXPECT_NE(rig.state(1), PreemptState::dwell);
  rig.run_to(40.0);
  EXPECT_EQ(rig.state(1), PreemptState::not_active);
  // Re-asserted every 5 s, it dwells until max presence (60 s), then exits and waits for the call
  // to be removed.
  const double start = rig.t;
  while (rig.t < start + 70.0) {
    rig.set(column(oid::kPreemptControlState, 1), 1);
    rig.run_to(rig.t + 5.0);
  }
  EXPECT_EQ(rig.state(1), PreemptState::max_presence);
  rig.run_to(rig.t + 15.0);
  EXPECT_TRUE(rig.controller.running_program(rig.node) || rig.controller.mode(rig.node) == preemption::SignalMode::program);
  rig.set(column(oid::kPreemptControlState, 1), 0);
  rig.set(column(oid::kPreemptControlState, 1), 1);
  EXPECT_EQ(rig.state(1), PreemptState::entry_started);
  EXPECT_TRUE(rig.monitor.violations().empty()) << rig.monitor.violations().front();
}

TEST(VirtualIntersection, PhaseControlServesTheHeldAndCalledPhases) {
  Rig rig;
  const maps::SignalPlan& plan = rig.plans.at(rig.node);
  // The east approach's through movement, held and called; the others forced off.
  std::optional<std::size_t> east;
  for (std::size_t m = 0; m < plan.movements.size(); ++m) {
    if (plan.movements[m].from == maps::Compass::east && plan.movements[m].turn == maps::Turn::through) east = m;
  }
  ASSERT_TRUE(east);
  const std::int64_t bit = 1ll << (*east % 8);
  const std::uint32_t group = static_cast<std::uint32_t>(*east / 8 + 1);
  rig.set(column(oid::kPhaseControlGroupHold, group), bit);
  rig.set(column(oid::kPhaseControlGroupVehCall, group), bit);
  rig.run_to(20.0);
  EXPECT_EQ(rig.controller.lights(rig.node)[*east], preemption::Light::green);
  rig.run_to(80.0);  // held: the program does not take it away
  EXPECT_EQ(rig.controller.lights(rig.node)[*east], preemption::Light::green);
  rig.set(column(oid::kPhaseControlGroupHold, group), 0);
  rig.set(column(oid::kPhaseControlGroupVehCall, group), 0);
  rig.run_to(100.0);
  EXPECT_EQ(rig.controller.mode(rig.node), preemption::SignalMode::program);
  EXPECT_TRUE(rig.monitor.violations().empty()) << rig.monitor.violations().front();
}

TEST(VirtualIntersection, SetsAreCheckedAndEveryObjectIsReachedInOrder) {
  Rig rig;
  const Value one{Value::Type::integer, 1, {}, {}};
  EXPECT_EQ(rig.x.check_set(column(oid::kPreemptState, 1), one), SetStatus::not_writable);
  EXPECT_EQ(rig.x.check_set(column(oid::kPreemptControlState, 1), Value{Value::Type::integer, 2, {}, {}}), SetStatus::wrong_value);
  EXPECT_EQ(rig.x.check_set(column(oid::kPreemptControlState, 1), Value{Value::Type::octets, 0, "on", {}}), SetStatus::wrong_type);
  EXPECT_EQ(rig.x.check_set(column(oid::kPreemptControlState, 9), one), SetStatus::no_such_object);
  EXPECT_EQ(rig.x.check_set(oid::kSysDescr, one), SetStatus::not_writable);
  EXPECT_FALSE(rig.x.get(column(oid::kPreemptState, 9), 0.0).has_value());
  EXPECT_EQ(rig.x.get(oid::kSysDescr, 0.0)->octets, "test");
  // GETNEXT from the root walks every object once, in increasing order, and ends.
  std::vector<Oid> walked;
  for (auto o = rig.x.next({1}); o; o = rig.x.next(*o)) walked.push_back(*o);
  ASSERT_FALSE(walked.empty());
  EXPECT_TRUE(std::is_sorted(walked.begin(), walked.end()));
  EXPECT_EQ(std::adjacent_find(walked.begin(), walked.end()), walked.end());
  EXPECT_EQ(walked.size(), 6u + 2 * 7u + 4 * 2u);  // scalars, 2 groups x 7 columns, 4 preempts x 2
  for (const Oid& o : walked) EXPECT_TRUE(rig.x.get(o, 0.0).has_value()) << to_string(o);
}

}  // namespace
}  // namespace corridor::ntcip
