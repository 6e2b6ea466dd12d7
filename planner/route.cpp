#include "planner/route.hpp"

#include <algorithm>

namespace corridor::planner {

std::optional<double> Route::cost_to_goal_s(NodeId node) const {
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    if (nodes[i] == node) return travel_time_s - arrival_s[i];
  }
  return std::nullopt;
}

Route make_route(const TravelCost& cost, EdgePoint start, std::vector<EdgeId> edges, EdgePoint goal) {
  const auto& g = cost.graph();
  Route r;
  r.start = start;
  r.goal = goal;
  r.edges = std::move(edges);
  if (r.edges.empty()) return r;
  if (r.edges.size() == 1) {
    r.travel_time_s = cost.partial_time_s(start.edge, start.offset_m, goal.offset_m);
    r.length_m = std::max(0.0, goal.offset_m - start.offset_m);
    r.turn_vertices.push_back(start.vertex());
  } else {
    double t = cost.partial_time_s(start.edge, start.offset_m, g.length_m(start.edge));
    double len = g.length_m(start.edge) - start.offset_m;
    // Follow the turn graph as the searches do, so that a via-way restriction's copies count.
    std::uint32_t vertex = start.vertex();
    r.turn_vertices.push_back(vertex);
    for (std::size_t i = 1; i < r.edges.size(); ++i) {
      const EdgeId e = r.edges[i];
      r.nodes.push_back(g.tail(e));
      r.arrival_s.push_back(t);
      const auto [turn, next] = cost.turn_onto(vertex, e);
      vertex = next;
      r.turn_vertices.push_back(vertex);
      if (i + 1 < r.edges.size()) {
        t = add_cost(t, add_cost(turn, cost.transit_s(e)));
        len += g.length_m(e);
      } else {
        t = add_cost(t, add_cost(turn, add_cost(cost.node_delay_s(g.tail(e)), cost.partial_time_s(e, 0.0, goal.offset_m))));
        len += goal.offset_m;
      }
    }
    r.travel_time_s = t;
    r.length_m = len;
  }
  r.found = r.travel_time_s < kInfCost;
  return r;
}

std::vector<maps::Point2> edge_polyline(const maps::RoadGraph& graph, EdgeId e, double from_m, double to_m) {
  const auto pts = graph.geometry(e);
  const double length = graph.length_m(e);
  double geometric = 0.0;
  for (std::size_t i = 1; i < pts.size(); ++i) geometric += maps::distance_m(pts[i - 1], pts[i]);
  const double scale = length > 0.0 ? geometric / length : 0.0;
  const double a = std::clamp(from_m, 0.0, length) * scale;
  const double b = std::clamp(to_m, 0.0, length) * scale;
  std::vector<maps::Point2> out;
  out.push_back(graph.point_along(e, from_m));
  double along = 0.0;
  for (std::size_t i = 1; i + 1 < pts.size(); ++i) {
    along += maps::distance_m(pts[i - 1], pts[i]);
    if (along > a && along < b) out.push_back(pts[i]);
  }
  out.push_back(graph.point_along(e, to_m));
  return out;
}

std::vector<maps::Point2> route_polyline(const maps::RoadGraph& graph, const Route& route,
                                         std::vector<std::uint32_t>* edge_first) {
  std::vector<maps::Point2> out;
  if (edge_first != nullptr) edge_first->clear();
  for (std::size_t i = 0; i < route.edges.size(); ++i) {
    if (edge_first != nullptr) edge_first->push_back(static_cast<std::uint32_t>(out.empty() ? 0 : out.size() - 1));
    const EdgeId e = route.edges[i];
    const double from = i == 0 ? route.start.offset_m : 0.0;
    const double to = i + 1 == route.edges.size() ? route.goal.offset_m : graph.length_m(e);
    auto part = edge_polyline(graph, e, from, to);
    // Consecutive edges share their junction point; keep it once.
    out.insert(out.end(), out.empty() ? part.begin() : part.begin() + 1, part.end());
  }
  return out;
}

}  // namespace corridor::planner
