// The route cost of a signal: E[Trans] and the mean red wait against a sampled timeline of the
// normal cycle, on hand-made and random plans; and the overlay gets the rule's value per plan.
#include "preemption/signal_costs.hpp"

#include <gtest/gtest.h>

#include <random>

#include <set>

#include "maps/intersection_geometry.hpp"
#include "maps/synthetic_grid.hpp"
#include "preemption/plan_movement.hpp"
#include "preemption/timing.hpp"
#include "tests/preemption/random_plans.hpp"

namespace corridor::preemption {
namespace {

// One cycle as segments: each program step's green, then its clearance (yellow + all-red). A
// movement is green in a clearance only when both neighbouring steps serve it.
struct Segment {
  double start, end;
  std::size_t step;
  bool clearance;
};

std::vector<Segment> timeline(const maps::SignalPlan& plan) {
  std::vector<Segment> out;
  double t = 0.0;
  for (std::size_t k = 0; k < plan.program.size(); ++k) {
    out.push_back({t, t + plan.program[k].green_s, k, false});
    t += plan.program[k].green_s;
    out.push_back({t, t + plan.yellow_s + plan.all_red_s, k, true});
    t += plan.yellow_s + plan.all_red_s;
  }
  return out;
}

bool green(const maps::SignalPlan& plan, const Segment& s, std::size_t movement) {
  const auto serves = [&](std::size_t k) { return plan.phases[plan.program[k].phase].serves(movement); };
  if (!s.clearance) return serves(s.step);
  return serves(s.step) && serves((s.step + 1) % plan.program.size());
}

// Sampled averages over arrivals every dt seconds of the cycle. For one movement (else for one that
// every phase conflicts with), an arrival while it shows green waits nothing.
constexpr std::size_t kConflicting = static_cast<std::size_t>(-1);
double sampled_transition(const maps::SignalPlan& plan, double dt, std::size_t movement = kConflicting) {
  double sum = 0.0;
  int n = 0;
  for (const Segment& s : timeline(plan)) {
    for (double u = s.start + dt / 2; u < s.end; u += dt, ++n) {
      if (movement != kConflicting && green(plan, s, movement)) continue;
      const double x = u - s.start;
      const double min_green = plan.phases[plan.program[s.step].phase].min_green_s;
      sum += s.clearance ? plan.yellow_s + plan.all_red_s - x : transition_time_s(min_green - x, plan.yellow_s, plan.all_red_s);
    }
  }
  return sum / n;
}

double sampled_red_wait(const maps::SignalPlan& plan, double dt, std::size_t only = kConflicting) {
  const auto one = timeline(plan);
  const double cycle = plan.cycle_s();
  double total = 0.0;
  for (std::size_t i = 0; i < plan.movements.size(); ++i) {
    if (only != kConflicting && i != only) continue;
    std::vector<Segment> two = one;  // two cycles, to find the next green after the first
    for (Segment s : one) two.push_back({s.start + cycle, s.end + cycle, s.step, s.clearance});
    double sum = 0.0;
    int n = 0;
    for (double u = dt / 2; u < cycle; u += dt, ++n) {
      double wait = cycle;  // never green
      for (const Segment& s : two) {
        if (s.end <= u || !green(plan, s, i) || s.end - s.start <= 0.0) continue;
        wait = std::max(0.0, s.start - u);
        break;
      }
      sum += wait;
    }
    total += sum / n;
  }
  return only != kConflicting ? total : total / static_cast<double>(plan.movements.size());
}

maps::SignalPlan two_phase_plan() {
  maps::SignalPlan plan;
  plan.node = NodeId{3};
  plan.movements = {{maps::Compass::north, maps::Compass::south, maps::Turn::through, 0},
                    {maps::Compass::east, maps::Compass::west, maps::Turn::through, 0}};
  plan.conflict = {0, 1, 1, 0};
  plan.phases = {{"NS", {1, 0}, 8.0}, {"EW", {0, 1}, 8.0}};
  plan.program = {{0, 30.0}, {1, 20.0}};
  plan.yellow_s = 3.0;
  plan.all_red_s = 2.0;
  return plan;
}

TEST(SignalCosts, TwoPhasePlanByHand) {
  const auto plan = two_phase_plan();  // cycle 30 + 5 + 20 + 5 = 60 s
  // Greens: 8²/2 + 30·5 + 5²/2 = 194.5 and 8²/2 + 20·5 + 5²/2 = 144.5, over 60 s.
  EXPECT_NEAR(expected_transition_s(plan), (194.5 + 144.5) / 60.0, 1e-12);
  // N-S is red 30 s a cycle, E-W 40 s: (30² + 40²) / (2 · 60) / 2.
  EXPECT_NEAR(expected_red_delay_s(plan), (900.0 / 120.0 + 1600.0 / 120.0) / 2.0, 1e-12);
  // Per movement. N-S is green in the 30 s step: its clearance after it (5²/2), then the E-W step
  // (8²/2 + 20·5) and its clearance (5²/2): 157 over 60 s. E-W: 8²/2 + 30·5 + 5²/2 + 5²/2 = 207.
  EXPECT_NEAR(expected_transition_s(plan, 0), 157.0 / 60.0, 1e-12);
  EXPECT_NEAR(expected_transition_s(plan, 1), 207.0 / 60.0, 1e-12);
  EXPECT_NEAR(expected_red_delay_s(plan, 0), 900.0 / 120.0, 1e-12);
  EXPECT_NEAR(expected_red_delay_s(plan, 1), 1600.0 / 120.0, 1e-12);
  // The longer green costs less, either way; no movement costs more than one always in conflict.
  EXPECT_LT(expected_transition_s(plan, 0), expected_transition_s(plan, 1));
  EXPECT_LT(expected_transition_s(plan, 1), expected_transition_s(plan));
  // A movement the plan does not have counts as always in conflict.
  EXPECT_DOUBLE_EQ(expected_transition_s(plan, 7), expected_transition_s(plan));
}

TEST(SignalCosts, ClosedFormsMatchASampledCycleOnRandomPlans) {
  std::mt19937_64 rng(11);
  for (int k = 0; k < 60; ++k) {
    const auto plan = testing::random_plan(rng, NodeId{static_cast<std::uint32_t>(k)});
    SCOPED_TRACE(k);
    EXPECT_NEAR(expected_transition_s(plan), sampled_transition(plan, 0.01), 0.01);
    EXPECT_NEAR(expected_red_delay_s(plan), sampled_red_wait(plan, 0.01), 0.02);
    for (std::size_t m = 0; m < plan.movements.size(); ++m) {
      EXPECT_NEAR(expected_transition_s(plan, m), sampled_transition(plan, 0.01, m), 0.01) << "movement " << m;
      EXPECT_NEAR(expected_red_delay_s(plan, m), sampled_red_wait(plan, 0.01, m), 0.02) << "movement " << m;
    }
    // Preempting a light never costs more than its minimum green plus clearance.
    double worst = 0.0;
    for (const auto& p : plan.phases) worst = std::max(worst, p.min_green_s);
    EXPECT_LE(expected_transition_s(plan), worst + plan.yellow_s + plan.all_red_s + 1e-9);
  }
}

// A 3 × 3 grid of two-way streets, and its one four-legged crossing (node ids follow a Hilbert
// order, so it is found, not assumed).
maps::RoadGraph crossing_grid() {
  maps::GridSpec spec;
  spec.rows = spec.cols = 3;
  spec.removal_fraction = spec.oneway_fraction = spec.diagonal_fraction = 0.0;
  return maps::make_perturbed_grid(spec);
}

NodeId crossing(const maps::RoadGraph& graph) {
  NodeId centre;
  for (NodeId v : graph.nodes()) {
    if (graph.in_edges(v).size() == 4) centre = v;
  }
  return centre;
}

TEST(SignalCosts, OverlayGetsEachMovementsValueByTheRule) {
  const maps::RoadGraph graph = crossing_grid();
  const NodeId centre = crossing(graph);
  ASSERT_TRUE(centre.valid());
  ASSERT_EQ(graph.in_edges(centre).size(), 4u);
  std::unordered_map<NodeId, maps::SignalPlan> plans;
  plans.emplace(centre, maps::make_nema_plan(centre, maps::legs_of(graph, centre)));
  const maps::SignalPlan& plan = plans.at(centre);
  planner::CostOverlay overlay(graph);
  overlay.set_node_delay(centre, 15.0);  // a flat delay set before is replaced by the movements'
  for (const SignalCostRule rule : {SignalCostRule::preempted, SignalCostRule::normal}) {
    set_signal_costs(overlay, graph, plans, rule);
    EXPECT_DOUBLE_EQ(overlay.node_delay_s(centre), 0.0);
    std::set<double> values;
    for (EdgeId in : graph.in_edges(centre)) {
      for (EdgeId out : graph.out_edges(centre)) {
        const auto m = plan_movement(graph, plan, in, out);
        ASSERT_TRUE(m.has_value());
        const double expected =
            rule == SignalCostRule::preempted ? expected_transition_s(plan, *m) : expected_red_delay_s(plan, *m);
        EXPECT_DOUBLE_EQ(overlay.turn_delay_s(in, out), expected);
        values.insert(expected);
      }
    }
    // NEMA's protected lefts get less green than the throughs beside them: the values differ, and
    // from every approach the left waits longer than going straight on.
    EXPECT_GE(values.size(), 2u);
    for (EdgeId in : graph.in_edges(centre)) {
      const maps::Compass from = maps::approach_side(graph, in);
      EdgeId straight, left;
      for (EdgeId out : graph.out_edges(centre)) {
        const int turn = (static_cast<int>(maps::exit_side(graph, out)) - static_cast<int>(from) + 4) % 4;
        if (turn == 2) straight = out;  // leaving by the opposite side
        if (turn == 1) left = out;      // from North (heading south), East is the driver's left
      }
      ASSERT_TRUE(straight.valid() && left.valid());
      EXPECT_GT(overlay.turn_delay_s(in, left), overlay.turn_delay_s(in, straight)) << "from " << maps::compass_letter(from);
    }
    // Nothing set at a node without a plan.
    const EdgeId corner_in = graph.in_edges(NodeId{0})[0];
    EXPECT_DOUBLE_EQ(overlay.turn_delay_s(corner_in, *graph.out_edges(NodeId{0}).begin()), 0.0);
  }
  // A preempted light costs less than waiting out its red, movement by movement.
  for (std::size_t m = 0; m < plan.movements.size(); ++m) {
    EXPECT_LT(expected_transition_s(plan, m), expected_red_delay_s(plan, m));
  }
}

// The movement a turn makes: by the plan's movement edges where it names them, else by compass.
TEST(PlanMovement, ByEdgeWhereNamedElseByCompass) {
  const maps::RoadGraph graph = crossing_grid();
  const NodeId centre = crossing(graph);
  ASSERT_TRUE(centre.valid());
  maps::SignalPlan plan = maps::make_nema_plan(centre, maps::legs_of(graph, centre));
  for (EdgeId in : graph.in_edges(centre)) {
    for (EdgeId out : graph.out_edges(centre)) {
      const auto m = plan_movement(graph, plan, in, out);
      ASSERT_TRUE(m.has_value());
      const maps::Compass from = maps::approach_side(graph, in);
      EXPECT_EQ(plan.movements[*m].from, from);
      if (maps::exit_side(graph, out) != from) {
        EXPECT_EQ(plan.movements[*m].to, maps::exit_side(graph, out));
      }
    }
  }
  // A U-turn is served with its approach's left turn.
  for (EdgeId in : graph.in_edges(centre)) {
    const maps::Compass from = maps::approach_side(graph, in);
    for (EdgeId out : graph.out_edges(centre)) {
      if (maps::exit_side(graph, out) != from) continue;
      const auto m = plan_movement(graph, plan, in, out);
      ASSERT_TRUE(m.has_value());
      EXPECT_EQ(plan.movements[*m].from, from);
      EXPECT_EQ(plan.movements[*m].turn, maps::Turn::left);
    }
  }
  // Named edges win over geometry.
  const EdgeId out = *graph.out_edges(centre).begin();
  plan.movement_edge.assign(plan.movements.size(), kInvalidEdge);
  plan.movement_edge[plan.movements.size() - 1] = out;
  EXPECT_EQ(plan_movement(graph, plan, graph.in_edges(centre)[0], out), plan.movements.size() - 1);
}

}  // namespace
}  // namespace corridor::preemption
