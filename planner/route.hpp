// A planned route: the edges driven from a start point to a goal point, with the predicted arrival
// time at every intersection on the way (which preemption needs), and its geometry.
#pragma once

#include <optional>
#include <span>
#include <vector>

#include "maps/geo.hpp"
#include "planner/travel_cost.hpp"

namespace corridor::planner {

struct Route {
  bool found = false;
  double travel_time_s = kInfCost;
  double length_m = 0.0;
  EdgePoint start;
  EdgePoint goal;
  std::vector<EdgeId> edges;      // edges.front() == start.edge, edges.back() == goal.edge
  std::vector<NodeId> nodes;      // intersections crossed, nodes[i] = head(edges[i])
  std::vector<double> arrival_s;  // from now until the vehicle reaches nodes[i]'s stop line
  // The turn-graph state on each edge (EdgePoint::turn_vertex): give it back with a start point on
  // edges[i], so a replan keeps what a via-way restriction remembers.
  std::vector<std::uint32_t> turn_vertices;

  // The point `offset_m` along edges[i], in the state the route drives it.
  [[nodiscard]] EdgePoint point_on(std::size_t i, double offset_m) const {
    return {edges[i], offset_m, i < turn_vertices.size() ? turn_vertices[i] : EdgePoint::kPlainEdge};
  }

  // Remaining travel time from arriving at `node` to the goal, if the route crosses it.
  [[nodiscard]] std::optional<double> cost_to_goal_s(NodeId node) const;
};

// Evaluates driving `edges` (first = start.edge, last = goal.edge) under the current costs.
Route make_route(const TravelCost& cost, EdgePoint start, std::vector<EdgeId> edges, EdgePoint goal);

// The route's polyline in the local frame, clipped at the start and goal offsets. With
// `edge_first`, also where each edge's piece starts in it (consecutive pieces share their junction).
std::vector<maps::Point2> route_polyline(const maps::RoadGraph& graph, const Route& route,
                                         std::vector<std::uint32_t>* edge_first = nullptr);

// The part of edge e between two offsets, as a polyline.
std::vector<maps::Point2> edge_polyline(const maps::RoadGraph& graph, EdgeId e, double from_m, double to_m);

}  // namespace corridor::planner
