#include "preemption/signal_costs.hpp"

#include <algorithm>

#include "preemption/timing.hpp"

namespace corridor::preemption {

double expected_transition_s(const maps::SignalPlan& plan) {
  const double cycle = plan.cycle_s();
  const double clearance = plan.yellow_s + plan.all_red_s;
  if (!(cycle > 0.0)) return transition_time_s(0.0, plan.yellow_s, plan.all_red_s);
  double integral = 0.0;
  for (const auto& step : plan.program) {
    const double g = std::max(0.0, step.green_s);
    const double m = step.phase < plan.phases.size() ? std::max(0.0, plan.phases[step.phase].min_green_s) : 0.0;
    // ∫_0^g max(0, m − u) du, then the constant yellow + all-red over the green, then the
    // clearance interval's own remainder, (Y+R)²/2.
    const double min_green_part = g >= m ? m * m / 2.0 : m * g - g * g / 2.0;
    integral += min_green_part + g * clearance + clearance * clearance / 2.0;
  }
  return integral / cycle;
}

double expected_red_delay_s(const maps::SignalPlan& plan) {
  const double cycle = plan.cycle_s();
  if (!(cycle > 0.0) || plan.movements.empty() || plan.program.empty()) return 0.0;
  const double clearance = plan.yellow_s + plan.all_red_s;
  const std::size_t n = plan.program.size();
  const auto serves = [&](std::size_t step, std::size_t movement) {
    const std::size_t phase = plan.program[step].phase;
    return phase < plan.phases.size() && plan.phases[phase].serves(movement);
  };
  double total = 0.0;
  for (std::size_t i = 0; i < plan.movements.size(); ++i) {
    // The cycle as red runs for movement i: each step's green, then its clearance, which stays
    // green only when the next step serves i too. A random arrival in a red run of r s waits r/2
    // on average, so the run adds r²/2; the run that wraps around the cycle's end is joined.
    std::vector<double> runs;
    double red = 0.0;
    for (std::size_t k = 0; k < n; ++k) {
      const double g = std::max(0.0, plan.program[k].green_s);
      if (serves(k, i)) {
        if (red > 0.0) runs.push_back(red);
        red = 0.0;
      } else {
        red += g;
      }
      if (serves(k, i) && serves((k + 1) % n, i)) {
        if (red > 0.0) runs.push_back(red);
        red = 0.0;
      } else {
        red += clearance;
      }
    }
    if (runs.size() == 0 && red >= cycle - 1e-9) {
      total += cycle;  // never green: the whole cycle's wait, bounded rather than infinite
      continue;
    }
    // The open run at the end continues into the first run of the cycle if the cycle starts red.
    if (!serves(0, i) && !runs.empty()) {
      runs.front() += red;
    } else if (red > 0.0) {
      runs.push_back(red);
    }
    for (double r : runs) total += r * r / (2.0 * cycle);
  }
  return total / static_cast<double>(plan.movements.size());
}

void set_signal_costs(planner::CostOverlay& overlay, const std::unordered_map<NodeId, maps::SignalPlan>& plans,
                      SignalCostRule rule) {
  for (const auto& [node, plan] : plans) {
    overlay.set_node_delay(node, rule == SignalCostRule::preempted ? expected_transition_s(plan) : expected_red_delay_s(plan));
  }
}

}  // namespace corridor::preemption
