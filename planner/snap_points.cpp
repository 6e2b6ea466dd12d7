#include "planner/snap_points.hpp"

#include "maps/errors.hpp"

namespace corridor::planner {

NodeId node_at_snap(const maps::RoadGraph& graph, const maps::SnapResult& snap) {
  const double len = graph.length_m(snap.edge);
  if (snap.offset_m <= kAtNodeM) return graph.tail(snap.edge);
  if (snap.offset_m >= len - kAtNodeM) return graph.head(snap.edge);
  return NodeId{};
}

bool at_same_node(const maps::RoadGraph& graph, const maps::SnapResult& a, const maps::SnapResult& b) {
  const NodeId n = node_at_snap(graph, a);
  return n.valid() && n == node_at_snap(graph, b);
}

std::vector<EdgePoint> points_from_snap(const maps::RoadGraph& graph, const maps::SnapResult& snap, PointRole role) {
  if (const NodeId n = node_at_snap(graph, snap); n.valid()) {
    std::vector<EdgePoint> at_node;
    if (role == PointRole::start) {
      for (EdgeId e : graph.out_edges(n)) at_node.push_back({e, 0.0});
    } else {
      for (EdgeId e : graph.in_edges(n)) at_node.push_back({e, graph.length_m(e)});
    }
    // A node with no edge in that direction (a sink or source left by a partial import) falls
    // back to the snapped road itself.
    if (!at_node.empty()) return at_node;
  }
  std::vector<EdgePoint> both{{snap.edge, snap.offset_m}};
  if (snap.twin.valid()) both.push_back({snap.twin, snap.twin_offset_m});
  return both;
}

std::optional<maps::SnapResult> main_component_snap(const maps::EdgeSnapper& snapper, const maps::RoadGraph& graph,
                                                    maps::LatLon p, const maps::SnapResult& nearest,
                                                    maps::SnapOptions options) {
  const std::size_t main = graph.main_component_nodes();
  if (graph.in_main_component(nearest.edge) || (main < kSmallComponentNodes && main <= graph.runner_up_component_nodes())) {
    return std::nullopt;
  }
  options.main_component_only = true;
  try {
    return snapper.snap(p, options);
  } catch (const maps::SnapError&) {
    return std::nullopt;  // no road of the main component within reach
  }
}

}  // namespace corridor::planner
