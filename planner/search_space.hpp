// The graph a route search runs on: the road graph's nodes plus a virtual start vertex S and goal
// vertex G, so that start and goal can be points on edges. Shared by Dijkstra, A* and D* Lite, so
// the three use one cost model and can serve as each other's oracles.
#pragma once

#include <span>
#include <vector>

#include "maps/ids.hpp"
#include "planner/route.hpp"
#include "planner/travel_cost.hpp"

namespace corridor::planner {

// Search vertices: graph node ids first, then S, then G.
using Vertex = StrongId<struct VertexTag, std::uint32_t, std::numeric_limits<std::uint32_t>::max()>;

class SearchSpace {
 public:
  // Starts and goals are alternative points (for example both directions of a two-way street).
  // Throws std::invalid_argument for an empty list, an unknown edge, or a non-finite offset.
  SearchSpace(const TravelCost& cost, std::vector<EdgePoint> starts, std::vector<EdgePoint> goals);

  [[nodiscard]] std::size_t vertex_count() const { return node_count_ + 2; }
  [[nodiscard]] Vertex start() const { return Vertex{static_cast<std::uint32_t>(node_count_)}; }
  [[nodiscard]] Vertex goal() const { return Vertex{static_cast<std::uint32_t>(node_count_ + 1)}; }
  [[nodiscard]] bool is_node(Vertex v) const { return v.index() < node_count_; }
  [[nodiscard]] static NodeId node(Vertex v) { return NodeId{v.v}; }
  [[nodiscard]] static Vertex vertex(NodeId n) { return Vertex{n.v}; }

  [[nodiscard]] std::span<const EdgePoint> starts() const { return starts_; }
  [[nodiscard]] std::span<const EdgePoint> goals() const { return goals_; }
  void set_starts(std::vector<EdgePoint> starts);

  [[nodiscard]] maps::Point2 position(Vertex v) const {
    if (is_node(v)) return cost_->graph().position(node(v));
    return v == start() ? start_pos_ : goal_pos_;
  }
  [[nodiscard]] double heuristic_s(Vertex a, Vertex b) const { return cost_->heuristic_s(position(a), position(b)); }
  [[nodiscard]] const TravelCost& cost() const { return *cost_; }

  // f(Vertex to, double cost_s, EdgeId via) for every arc out of u. `via` is the road edge the arc
  // drives on (for S and G arcs, the start or goal edge).
  template <class F>
  void for_each_successor(Vertex u, F&& f) const {
    const auto& g = cost_->graph();
    if (u == start()) {
      for (const EdgePoint& s : starts_) {
        f(vertex(g.head(s.edge)), cost_->partial_time_s(s.edge, s.offset_m, g.length_m(s.edge)), s.edge);
        for (const EdgePoint& t : goals_) {
          if (t.edge == s.edge && t.offset_m >= s.offset_m) f(goal(), cost_->partial_time_s(s.edge, s.offset_m, t.offset_m), s.edge);
        }
      }
      return;
    }
    if (u == goal()) return;
    const NodeId n = node(u);
    for (EdgeId e : g.out_edges(n)) f(vertex(g.head(e)), cost_->transit_s(e), e);
    for (const EdgePoint& t : goals_) {
      if (g.tail(t.edge) == n) f(goal(), goal_arc_s(t), t.edge);
    }
  }

  // f(Vertex from, double cost_s) for every arc into v.
  template <class F>
  void for_each_predecessor(Vertex v, F&& f) const {
    const auto& g = cost_->graph();
    if (v == start()) return;
    if (v == goal()) {
      for (const EdgePoint& t : goals_) f(vertex(g.tail(t.edge)), goal_arc_s(t));
      for (const EdgePoint& s : starts_) {
        for (const EdgePoint& t : goals_) {
          if (t.edge == s.edge && t.offset_m >= s.offset_m) f(start(), cost_->partial_time_s(s.edge, s.offset_m, t.offset_m));
        }
      }
      return;
    }
    const NodeId n = node(v);
    for (EdgeId e : g.in_edges(n)) f(vertex(g.tail(e)), cost_->transit_s(e));
    for (const EdgePoint& s : starts_) {
      if (g.head(s.edge) == n) f(start(), cost_->partial_time_s(s.edge, s.offset_m, g.length_m(s.edge)));
    }
  }

  // The route driving `edges` (the via edges of a path of arcs from S to G), between the start and
  // goal points on its first and last edge.
  [[nodiscard]] Route route_along(std::vector<EdgeId> edges) const;

  // True when a change of this edge's cost changes an arc out of S.
  [[nodiscard]] bool is_start_edge(EdgeId e) const;

 private:
  // Crossing the goal edge's tail intersection, then driving to the goal point.
  [[nodiscard]] double goal_arc_s(const EdgePoint& t) const {
    return add_cost(cost_->node_delay_s(cost_->graph().tail(t.edge)), cost_->partial_time_s(t.edge, 0.0, t.offset_m));
  }
  // Checks ids and clamps offsets onto their edges.
  void normalize(std::vector<EdgePoint>& points, const char* what) const;

  const TravelCost* cost_;
  std::size_t node_count_;
  std::vector<EdgePoint> starts_;
  std::vector<EdgePoint> goals_;
  maps::Point2 start_pos_;
  maps::Point2 goal_pos_;
};

}  // namespace corridor::planner
