// The graph a route search runs on: the road graph's nodes plus a virtual start vertex S and goal
// vertex G, so that start and goal can be points on edges. Shared by Dijkstra, A* and D* Lite, so
// the three use one cost model and can serve as each other's oracles.
#pragma once

#include <algorithm>
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

  // The road nodes S's arcs lead to and G's arcs come from.
  [[nodiscard]] std::span<const NodeId> start_heads() const { return start_heads_; }
  [[nodiscard]] std::span<const NodeId> goal_tails() const { return goal_tails_; }

  // Consistent lower bounds on the cost from S to v (D* Lite's backward search) and from v to G
  // (A*'s forward search). Every path from S leaves through a start head, every path to G arrives
  // through a goal tail, and the arcs from S and to G cost at least 0, so the minimum of the
  // landmark bound over those nodes is admissible; a minimum of consistent bounds is consistent.
  [[nodiscard]] double h_from_start_s(Vertex v) const {
    if (!is_node(v)) return 0.0;
    double best = kInfCost;
    for (NodeId a : start_heads_) best = std::min(best, cost_->lower_bound_s(a, node(v)));
    return best;
  }
  [[nodiscard]] double h_to_goal_s(Vertex v) const {
    if (!is_node(v)) return 0.0;
    double best = kInfCost;
    for (NodeId b : goal_tails_) best = std::min(best, cost_->lower_bound_s(node(v), b));
    return best;
  }
  // How much h_from_start_s can fall, at any vertex, when the start moves from `old_heads` to the
  // current ones: max over new heads b of min over old heads a of bound(a, b). D* Lite adds it to
  // its key modifier km, which keeps queued keys lower bounds (the landmark bound obeys the triangle
  // inequality; see docs/routing.md).
  [[nodiscard]] double start_shift_s(std::span<const NodeId> old_heads) const;
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
  std::vector<NodeId> start_heads_;
  std::vector<NodeId> goal_tails_;
};

}  // namespace corridor::planner
