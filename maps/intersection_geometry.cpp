#include "maps/intersection_geometry.hpp"

#include <cmath>

namespace corridor::maps {
namespace {

// Sectors of 90° centred on the compass directions; y is north, x is east.
Compass side_of(Point2 from_node, Point2 toward) {
  const double angle = std::atan2(toward.y_m - from_node.y_m, toward.x_m - from_node.x_m) * 180.0 / M_PI;
  if (angle >= 45.0 && angle < 135.0) return Compass::north;
  if (angle >= -45.0 && angle < 45.0) return Compass::east;
  if (angle >= -135.0 && angle < -45.0) return Compass::south;
  return Compass::west;
}

}  // namespace

Compass approach_side(const RoadGraph& graph, EdgeId in_edge) {
  const auto pts = graph.geometry(in_edge);
  // The last bend before the node tells the side; the far end may curve away.
  return side_of(pts.back(), pts[pts.size() - 2]);
}

Compass exit_side(const RoadGraph& graph, EdgeId out_edge) {
  const auto pts = graph.geometry(out_edge);
  return side_of(pts.front(), pts[1]);
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
