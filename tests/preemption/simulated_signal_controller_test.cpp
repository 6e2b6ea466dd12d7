#include "preemption/simulated_signal_controller.hpp"

#include <gtest/gtest.h>

#include <random>

#include "preemption/phase_selection.hpp"
#include "preemption/safety_monitor.hpp"
#include "tests/preemption/random_plans.hpp"

namespace corridor::preemption {
namespace {

struct Rig {
  std::unordered_map<NodeId, maps::SignalPlan> plans;
  std::unique_ptr<SimulatedSignalController> controller;
  SafetyMonitor monitor;

  explicit Rig(maps::SignalPlan plan) {
    const NodeId node = plan.node;
    plans.emplace(node, std::move(plan));
    controller = std::make_unique<SimulatedSignalController>(plans, 0.0);
    monitor.watch(plans.at(node), controller->lights(node), 0.0);
    controller->set_observer([this](NodeId n, const std::vector<Light>& l, double t) { monitor.observe(n, l, t); });
  }
};

TEST(SimulatedSignalController, RunsTheNormalProgramSafely) {
  Rig rig(maps::make_nema_plan(NodeId{3}));
  const auto& plan = rig.plans.at(NodeId{3});
  std::vector<std::size_t> steps_seen;
  for (double t = 0; t <= 3 * plan.cycle_s(); t += 0.5) {
    rig.controller->advance(t);
    const std::size_t step = rig.controller->program_step(NodeId{3});
    if (steps_seen.empty() || steps_seen.back() != step) steps_seen.push_back(step);
  }
  EXPECT_TRUE(rig.monitor.violations().empty()) << rig.monitor.violations().front();
  EXPECT_GE(steps_seen.size(), 3 * plan.program.size());  // it cycles through every step
  EXPECT_GT(rig.monitor.changes_observed(), 10u);
}

// Hand-timed: 4+7 is green from 0 s (min green 5 s). A hold of 3+8 at 1 s must wait for the min
// green (5 s), then show yellow for 3 s and all-red for 2 s, so 3+8 is green at 10 s.
TEST(SimulatedSignalController, HoldHonoursMinGreenYellowAndAllRed) {
  Rig rig(maps::make_nema_plan(NodeId{3}));
  const auto& plan = rig.plans.at(NodeId{3});
  const std::size_t target = *plan.phase_index("3+8");
  const std::size_t s_n = *plan.movement_index(maps::Compass::south, maps::Compass::north);
  const std::size_t n_e = *plan.movement_index(maps::Compass::north, maps::Compass::east);
  rig.controller->hold(NodeId{3}, plan.phases[target], 1.0);
  EXPECT_EQ(rig.controller->mode(NodeId{3}), SignalMode::held);
  rig.controller->advance(4.99);
  EXPECT_EQ(rig.controller->lights(NodeId{3})[n_e], Light::green);
  rig.controller->advance(5.0);
  EXPECT_EQ(rig.controller->lights(NodeId{3})[n_e], Light::yellow);
  rig.controller->advance(7.99);
  EXPECT_EQ(rig.controller->lights(NodeId{3})[n_e], Light::yellow);
  rig.controller->advance(8.0);
  EXPECT_EQ(rig.controller->lights(NodeId{3})[n_e], Light::red);
  EXPECT_EQ(rig.controller->lights(NodeId{3})[s_n], Light::red);
  rig.controller->advance(9.99);
  EXPECT_EQ(rig.controller->lights(NodeId{3})[s_n], Light::red);
  rig.controller->advance(10.0);
  EXPECT_EQ(rig.controller->lights(NodeId{3})[s_n], Light::green);
  EXPECT_EQ(rig.controller->current_phase(NodeId{3}), target);
  rig.controller->advance(500.0);  // held: it stays
  EXPECT_EQ(rig.controller->current_phase(NodeId{3}), target);
  rig.controller->release(NodeId{3}, 0, 500.0);
  rig.controller->advance(500.0 + 5.0 + plan.yellow_s + plan.all_red_s);
  EXPECT_TRUE(rig.controller->running_program(NodeId{3}));
  EXPECT_EQ(rig.controller->program_step(NodeId{3}), 0u);
  EXPECT_TRUE(rig.monitor.violations().empty()) << rig.monitor.violations().front();
}

TEST(SimulatedSignalController, RefusesUnsafePhasesAndUnknownNodes) {
  Rig rig(maps::make_nema_plan(NodeId{3}));
  const auto& plan = rig.plans.at(NodeId{3});
  maps::Phase unsafe = plan.phases[0];
  for (auto& g : unsafe.green) g = 1;
  EXPECT_THROW(rig.controller->hold(NodeId{3}, unsafe, 1.0), std::invalid_argument);
  EXPECT_THROW(rig.controller->hold(NodeId{4}, plan.phases[0], 1.0), std::invalid_argument);
  EXPECT_EQ(rig.controller->mode(NodeId{3}), SignalMode::program);
}

// Thousands of random plans, each driven by a random sequence of holds (plan phases and
// synthesized ones) and releases at random times. The monitor sees every light change.
TEST(SimulatedSignalController, RandomCommandsNeverBreakSafetyAndAlwaysRecover) {
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int plans = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    Rig rig(testing::random_plan(rng, NodeId{7}));
    const auto& plan = rig.plans.at(NodeId{7});
    double t = 0.0;
    for (int k = 0; k < 25; ++k) {
      t += unit(rng) < 0.3 ? unit(rng) * 0.5 : unit(rng) * 20.0;  // some commands come in bursts
      const double r = unit(rng);
      if (r < 0.6) {
        const std::size_t m = rng() % plan.movements.size();
        const auto level = unit(rng) < 0.5 ? CongestionLevel::low : CongestionLevel::high;
        rig.controller->hold(NodeId{7}, select_phase(plan, m, rig.controller->current_phase(NodeId{7}), level).phase, t);
      } else if (r < 0.9) {
        rig.controller->release(NodeId{7}, rng() % plan.program.size(), t);
      } else {
        rig.controller->advance(t);
      }
    }
    const bool was_held = rig.controller->mode(NodeId{7}) == SignalMode::held;
    rig.controller->release(NodeId{7}, 0, t);  // a no-op when the program already runs
    EXPECT_EQ(rig.controller->mode(NodeId{7}), SignalMode::program);
    double max_min_green = 0;
    for (const auto& p : plan.phases) max_min_green = std::max(max_min_green, p.min_green_s);
    // Back in the normal program: the resumed step's phase is on show within one min green and two
    // clearances, before the program can have moved past it.
    bool resumed = false;
    for (double u = t; u <= t + max_min_green + 2 * (plan.yellow_s + plan.all_red_s) + 1e-6; u += 0.25) {
      rig.controller->advance(u);
      resumed = resumed || (rig.controller->running_program(NodeId{7}) &&
                            (!was_held || rig.controller->program_step(NodeId{7}) == 0));
    }
    ASSERT_TRUE(resumed) << "trial " << trial;
    rig.controller->advance(t + 2 * plan.cycle_s() + 100.0);
    ASSERT_TRUE(rig.monitor.violations().empty()) << "trial " << trial << ": " << rig.monitor.violations().front();
    ++plans;
  }
  EXPECT_EQ(plans, 2000);
}

// The monitor itself must catch what it is there to catch.
TEST(SafetyMonitor, DetectsEachKindOfViolation) {
  const auto plan = maps::make_nema_plan(NodeId{1});
  const std::size_t n = plan.movements.size();
  const std::size_t n_s = *plan.movement_index(maps::Compass::north, maps::Compass::south);
  const std::size_t e_w = *plan.movement_index(maps::Compass::east, maps::Compass::west);
  std::vector<Light> all_red(n, Light::red);
  {
    SafetyMonitor m;
    m.watch(plan, all_red, 0.0);
    auto l = all_red;
    l[n_s] = l[e_w] = Light::green;
    m.observe(plan.node, l, 10.0);
    EXPECT_FALSE(m.violations().empty());  // conflicting greens
  }
  {
    SafetyMonitor m;
    auto l = all_red;
    l[n_s] = Light::green;
    m.watch(plan, l, 0.0);
    l[n_s] = Light::red;
    m.observe(plan.node, l, 30.0);
    EXPECT_FALSE(m.violations().empty());  // green to red without yellow
  }
  {
    SafetyMonitor m;
    auto l = all_red;
    l[n_s] = Light::green;
    m.watch(plan, l, 0.0);
    l[n_s] = Light::yellow;
    m.observe(plan.node, l, 30.0);
    l[n_s] = Light::red;
    m.observe(plan.node, l, 31.0);  // yellow shorter than 3 s
    EXPECT_FALSE(m.violations().empty());
  }
  {
    SafetyMonitor m;
    auto l = all_red;
    l[n_s] = Light::green;
    m.watch(plan, l, 0.0);
    l[n_s] = Light::yellow;
    m.observe(plan.node, l, 30.0);
    l[n_s] = Light::red;
    m.observe(plan.node, l, 33.0);
    l[e_w] = Light::green;
    m.observe(plan.node, l, 34.0);  // 1 s after the conflict turned red: under the 2 s all-red
    EXPECT_FALSE(m.violations().empty());
  }
  {
    SafetyMonitor m;
    auto l = all_red;
    m.watch(plan, l, 0.0);
    l[n_s] = Light::green;
    m.observe(plan.node, l, 10.0);
    l[n_s] = Light::yellow;
    m.observe(plan.node, l, 12.0);  // green for 2 s: under the min green
    EXPECT_FALSE(m.violations().empty());
  }
}

}  // namespace
}  // namespace corridor::preemption
