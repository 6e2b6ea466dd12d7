#include "preemption/signal_costs.hpp"

#include <algorithm>

#include "preemption/plan_movement.hpp"
#include "preemption/timing.hpp"

namespace corridor::preemption {

namespace {

constexpr std::size_t kNoMovement = static_cast<std::size_t>(-1);

bool serves(const maps::SignalPlan& plan, std::size_t step, std::size_t movement) {
  if (movement == kNoMovement) return false;
  const std::size_t phase = plan.program[step].phase;
  return phase < plan.phases.size() && plan.phases[phase].serves(movement);
}

// E[Trans] for `movement`, or for a movement that every phase conflicts with (kNoMovement).
double transition_for(const maps::SignalPlan& plan, std::size_t movement) {
  const double cycle = plan.cycle_s();
  const double clearance = plan.yellow_s + plan.all_red_s;
  if (!(cycle > 0.0) || plan.program.empty()) return transition_time_s(0.0, plan.yellow_s, plan.all_red_s);
  const std::size_t n = plan.program.size();
  double integral = 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    const auto& step = plan.program[k];
    const double g = std::max(0.0, step.green_s);
    const double m = step.phase < plan.phases.size() ? std::max(0.0, plan.phases[step.phase].min_green_s) : 0.0;
    const bool green = serves(plan, k, movement);
    // An arrival in a green that serves the movement is not held (the controller keeps it). Else
    // ∫_0^g max(0, m − u) du, plus the constant yellow + all-red over the green.
    if (!green) integral += (g >= m ? m * m / 2.0 : m * g - g * g / 2.0) + g * clearance;
    // The clearance interval after the step: green throughout when the next step serves the
    // movement too; otherwise what is left of it, (Y+R)²/2.
    if (!(green && serves(plan, (k + 1) % n, movement))) integral += clearance * clearance / 2.0;
  }
  return integral / cycle;
}

}  // namespace

double expected_transition_s(const maps::SignalPlan& plan) { return transition_for(plan, kNoMovement); }

double expected_transition_s(const maps::SignalPlan& plan, std::size_t movement) {
  return transition_for(plan, movement < plan.movements.size() ? movement : kNoMovement);
}

double expected_red_delay_s(const maps::SignalPlan& plan, std::size_t i) {
  const double cycle = plan.cycle_s();
  if (!(cycle > 0.0) || i >= plan.movements.size() || plan.program.empty()) return 0.0;
  const double clearance = plan.yellow_s + plan.all_red_s;
  const std::size_t n = plan.program.size();
  // The cycle as red runs for movement i: each step's green, then its clearance, which stays green
  // only when the next step serves i too. A random arrival in a red run of r s waits r/2 on
  // average, so the run adds r²/2; the run that wraps around the cycle's end is joined.
  std::vector<double> runs;
  double red = 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    const double g = std::max(0.0, plan.program[k].green_s);
    if (serves(plan, k, i)) {
      if (red > 0.0) runs.push_back(red);
      red = 0.0;
      if (!serves(plan, (k + 1) % n, i)) red += clearance;
    } else {
      red += g + clearance;
    }
  }
  if (runs.empty() && red >= cycle - 1e-9) return cycle;  // never green: a whole cycle, bounded
  // The open run at the end continues into the first run of the cycle if the cycle starts red.
  if (!serves(plan, 0, i) && !runs.empty()) {
    runs.front() += red;
  } else if (red > 0.0) {
    runs.push_back(red);
  }
  double total = 0.0;
  for (double r : runs) total += r * r / (2.0 * cycle);
  return total;
}

double expected_red_delay_s(const maps::SignalPlan& plan) {
  if (plan.movements.empty()) return 0.0;
  double total = 0.0;
  for (std::size_t i = 0; i < plan.movements.size(); ++i) total += expected_red_delay_s(plan, i);
  return total / static_cast<double>(plan.movements.size());
}

void set_signal_costs(planner::CostOverlay& overlay, const maps::RoadGraph& graph,
                      const std::unordered_map<NodeId, maps::SignalPlan>& plans, SignalCostRule rule) {
  for (const auto& [node, plan] : plans) {
    // The wait belongs to the movement: the node itself adds nothing on top.
    overlay.set_node_delay(node, 0.0);
    for (EdgeId in : graph.in_edges(node)) {
      for (EdgeId out : graph.out_edges(node)) {
        const std::optional<std::size_t> m = plan_movement(graph, plan, in, out);
        double delay = 0.0;
        if (rule == SignalCostRule::preempted) {
          delay = m ? expected_transition_s(plan, *m) : expected_transition_s(plan);
        } else {
          delay = m ? expected_red_delay_s(plan, *m) : expected_red_delay_s(plan);
        }
        overlay.set_turn_delay(in, out, delay);
      }
    }
  }
}

}  // namespace corridor::preemption
