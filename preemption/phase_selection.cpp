#include "preemption/phase_selection.hpp"

#include <algorithm>
#include <cmath>

namespace corridor::preemption {
namespace {

double default_weight(const maps::Movement& m) { return m.turn == maps::Turn::left ? 1.0 : 2.0; }

// How well a phase serves traffic on approaches other than the vehicle's: measured demand first,
// then the through-before-left weights.
std::pair<double, double> other_approach_score(const maps::SignalPlan& plan, const maps::Phase& phase,
                                               maps::Compass vehicle_from, std::span<const double> demand) {
  double measured = 0.0, weight = 0.0;
  for (std::size_t m = 0; m < plan.movements.size(); ++m) {
    if (!phase.serves(m) || plan.movements[m].from == vehicle_from) continue;
    if (m < demand.size() && std::isfinite(demand[m])) measured += demand[m];
    weight += default_weight(plan.movements[m]);
  }
  return {measured, weight};
}

std::size_t approach_movements_served(const maps::SignalPlan& plan, const maps::Phase& phase, maps::Compass from) {
  std::size_t n = 0;
  for (std::size_t m = 0; m < plan.movements.size(); ++m) n += phase.serves(m) && plan.movements[m].from == from ? 1 : 0;
  return n;
}

maps::Phase synthesize(const maps::SignalPlan& plan, std::size_t movement, std::span<const std::size_t> also) {
  maps::Phase phase;
  phase.label = "preempt:" + plan.movements[movement].label();
  phase.green.assign(plan.movements.size(), 0);
  phase.green[movement] = 1;
  for (std::size_t m : also) {
    // The vehicle's own later movements, where they conflict with nothing already green.
    bool compatible = true;
    for (std::size_t g = 0; g < plan.movements.size(); ++g) compatible = compatible && !(phase.green[g] && plan.conflicts(g, m));
    if (!compatible || phase.green[m]) continue;
    phase.green[m] = 1;
    phase.label += "+" + plan.movements[m].label();
  }
  phase.min_green_s = plan.phases.empty() ? 5.0 : plan.phases.front().min_green_s;
  auto add_compatible = [&](bool same_approach) {
    for (std::size_t m = 0; m < plan.movements.size(); ++m) {
      if ((plan.movements[m].from == plan.movements[movement].from) != same_approach || phase.green[m]) continue;
      bool compatible = true;
      for (std::size_t g = 0; g < plan.movements.size(); ++g) compatible = compatible && !(phase.green[g] && plan.conflicts(g, m));
      if (compatible) phase.green[m] = 1;
    }
  };
  // First the vehicle's own approach, so the queue in front of it moves; then whatever else
  // conflicts with nothing green, so the hold stops no more traffic than it must.
  add_compatible(true);
  add_compatible(false);
  return phase;
}

}  // namespace

PhaseDecision select_phase(const maps::SignalPlan& plan, std::size_t movement, std::optional<std::size_t> current,
                           CongestionLevel level, std::span<const double> demand, std::span<const std::size_t> also) {
  const maps::Compass from = plan.movements.at(movement).from;
  std::vector<std::size_t> candidates;
  for (std::size_t p = 0; p < plan.phases.size(); ++p) {
    const bool serves_all = std::all_of(also.begin(), also.end(), [&](std::size_t m) { return plan.phases[p].serves(m); });
    if (plan.phases[p].serves(movement) && serves_all && plan.phase_is_safe(plan.phases[p])) candidates.push_back(p);
  }
  if (candidates.empty()) return {synthesize(plan, movement, also), std::nullopt, false};

  // Only a safe phase that serves the movement may be extended; a SUMO phase with permissive
  // greens serves it but is not safe to hold.
  const bool current_is_candidate =
      current && std::find(candidates.begin(), candidates.end(), *current) != candidates.end();
  std::size_t best = candidates.front();
  if (level == CongestionLevel::high) {
    // Every movement of the approach, so the queue in front of the vehicle discharges with it.
    for (std::size_t p : candidates) {
      if (approach_movements_served(plan, plan.phases[p], from) > approach_movements_served(plan, plan.phases[best], from)) best = p;
    }
    if (current_is_candidate && approach_movements_served(plan, plan.phases[*current], from) ==
                                    approach_movements_served(plan, plan.phases[best], from)) {
      best = *current;
    }
  } else {
    if (current_is_candidate) return {plan.phases[*current], *current, true};
    for (std::size_t p : candidates) {
      if (other_approach_score(plan, plan.phases[p], from, demand) > other_approach_score(plan, plan.phases[best], from, demand)) {
        best = p;
      }
    }
  }
  return {plan.phases[best], best, current && *current == best};
}

DecisionTables nema_decision_tables() {
  const maps::SignalPlan plan = maps::make_nema_plan(NodeId{0});
  DecisionTables t;
  for (const auto& m : plan.movements) t.movements.push_back(m.label());
  for (const auto& p : plan.phases) t.phases.push_back(p.label);
  for (std::size_t m = 0; m < plan.movements.size(); ++m) {
    std::vector<std::string> high_row, low_row;
    for (std::size_t p = 0; p < plan.phases.size(); ++p) {
      high_row.push_back(select_phase(plan, m, p, CongestionLevel::high).phase.label);
      low_row.push_back(select_phase(plan, m, p, CongestionLevel::low).phase.label);
    }
    t.high.push_back(std::move(high_row));
    t.low.push_back(std::move(low_row));
  }
  return t;
}

}  // namespace corridor::preemption
