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
  if (auto m = plan.movement_index(from, maps::exit_side(graph, out_edge))) return m;
  for (std::size_t m = 0; m < plan.movements.size(); ++m) {
    if (plan.movements[m].from == from) return m;
  }
  return std::nullopt;
}

}  // namespace corridor::preemption
