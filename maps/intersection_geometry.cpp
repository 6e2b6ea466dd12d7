#include "maps/intersection_geometry.hpp"

#include <cmath>

namespace corridor::maps {
namespace {


}  // namespace

Compass approach_side(const RoadGraph& graph, EdgeId in_edge) {
  const auto pts = graph.geometry(in_edge);
  // The last bend before the node tells the side; the far end may curve away.
  return compass_side(pts.back(), pts[pts.size() - 2]);
}

Compass exit_side(const RoadGraph& graph, EdgeId out_edge) {
  const auto pts = graph.geometry(out_edge);
  return compass_side(pts.front(), pts[1]);
}

std::uint8_t legs_of(const RoadGraph& graph, NodeId node) {
  std::uint8_t legs = 0;
  for (EdgeId e : graph.in_edges(node)) legs |= static_cast<std::uint8_t>(1u << static_cast<int>(approach_side(graph, e)));
  for (EdgeId e : graph.out_edges(node)) legs |= static_cast<std::uint8_t>(1u << static_cast<int>(exit_side(graph, e)));
  return legs;
}

std::unordered_map<NodeId, SignalPlan> default_signal_plans(const RoadGraph& graph, const NemaTiming& timing) {
  std::unordered_map<NodeId, SignalPlan> plans;
  for (NodeId v : graph.nodes()) {
    if (!graph.signalized(v)) continue;
    SignalPlan plan = make_nema_plan(v, legs_of(graph, v), timing);
    if (!plan.program.empty()) plans.emplace(v, std::move(plan));
  }
  return plans;
}

}  // namespace corridor::maps
