#include "preemption/plan_movement.hpp"

#include <algorithm>

#include "maps/intersection_geometry.hpp"

namespace corridor::preemption {

std::optional<std::size_t> plan_movement(const maps::RoadGraph& graph, const maps::SignalPlan& plan, EdgeId in_edge,
                                         EdgeId out_edge) {
  if (!plan.movement_edge.empty()) {
    const auto it = std::find(plan.movement_edge.begin(), plan.movement_edge.end(), out_edge);
    if (it != plan.movement_edge.end()) return static_cast<std::size_t>(it - plan.movement_edge.begin());
  }
  const maps::Compass from = maps::approach_side(graph, in_edge);
  const maps::Compass to = maps::exit_side(graph, out_edge);
  if (auto m = plan.movement_index(from, to)) return m;
  // A U-turn is made from the left lane, on the left turn's green. For a leg the plan merged, the
  // approach's first movement stands for it.
  std::optional<std::size_t> first;
  for (std::size_t m = 0; m < plan.movements.size(); ++m) {
    if (plan.movements[m].from != from) continue;
    if (to == from && plan.movements[m].turn == maps::Turn::left) return m;
    if (!first) first = m;
  }
  return first;
}

}  // namespace corridor::preemption
