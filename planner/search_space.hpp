// The graph a route search runs on: the road graph's edge-based turn graph (maps/turn_graph.hpp),
// a vertex per directed edge standing at its head, plus a virtual start vertex S and goal vertex G,
// so that start and goal can be points on edges and every turn on the way is one the vehicle may
// make. Shared by Dijkstra, A* and D* Lite, so the three use one cost model and can serve as each
// other's oracles.
#pragma once

#include <algorithm>
#include <span>
#include <vector>

#include "maps/ids.hpp"
#include "planner/route.hpp"
#include "planner/travel_cost.hpp"

namespace corridor::planner {

// Search vertices: the turn graph's vertices first (edges, then the copies via-way restrictions
// need), then S, then G.
using Vertex = StrongId<struct VertexTag, std::uint32_t, std::numeric_limits<std::uint32_t>::max()>;

class SearchSpace {
 public:
  using Via = EdgeId;  // the road edge an arc drives on
  using Source = TravelCost;

  // Starts and goals are alternative points (for example both directions of a two-way street).
  // Throws std::invalid_argument for an empty list, an unknown edge, or a non-finite offset.
  SearchSpace(const TravelCost& cost, std::vector<EdgePoint> starts, std::vector<EdgePoint> goals);

  [[nodiscard]] std::size_t vertex_count() const { return turn_vertices_ + 2; }
  // The most arcs a path from S to G can take without visiting a vertex twice.
  [[nodiscard]] std::size_t max_path_arcs() const { return vertex_count(); }
  [[nodiscard]] Vertex start() const { return Vertex{static_cast<std::uint32_t>(turn_vertices_)}; }
  [[nodiscard]] Vertex goal() const { return Vertex{static_cast<std::uint32_t>(turn_vertices_ + 1)}; }
  [[nodiscard]] bool is_turn_vertex(Vertex v) const { return v.index() < turn_vertices_; }
  // The road edge a turn vertex has driven, and the intersection it stands at (its head).
  [[nodiscard]] EdgeId edge(Vertex v) const { return turns_->edge_of(v.v); }
  [[nodiscard]] NodeId node(Vertex v) const { return cost_->graph().head(edge(v)); }
  // The vertex of having driven e (not one of its copies).
  [[nodiscard]] static Vertex vertex(EdgeId e) { return Vertex{e.v}; }
  // The vertices whose arcs' costs a change to edge e's conditions changes: every source of a turn
  // onto e or onto one of its copies. f(Vertex).
  template <class F>
  void for_each_vertex_turning_onto(EdgeId e, F&& f) const {
    for (const maps::TurnArc& a : turns_->arcs_in(e.v)) f(Vertex{a.other});
    for (std::uint32_t c : turns_->copies_of(e)) {
      for (const maps::TurnArc& a : turns_->arcs_in(c)) f(Vertex{a.other});
    }
  }
  // The vertices standing at node n (whose arcs cross it): its in-edges and their copies.
  template <class F>
  void for_each_vertex_at(NodeId n, F&& f) const {
    for (EdgeId e : cost_->graph().in_edges(n)) {
      f(vertex(e));
      for (std::uint32_t c : turns_->copies_of(e)) f(Vertex{c});
    }
  }

  [[nodiscard]] std::span<const EdgePoint> starts() const { return starts_; }
  [[nodiscard]] std::span<const EdgePoint> goals() const { return goals_; }
  void set_starts(std::vector<EdgePoint> starts);
  // The vehicle moved (D* Lite): set_starts, and how far the heuristic can fall anywhere with it,
  // which D* Lite adds to its key modifier (start_shift_s from the old heads).
  double move_starts(std::vector<EdgePoint> starts);
  // What the starts, goals and their nodes hold on the heap.
  [[nodiscard]] std::size_t heap_bytes() const {
    return (starts_.capacity() + goals_.capacity()) * sizeof(EdgePoint) +
           (start_heads_.capacity() + goal_tails_.capacity() + old_heads_.capacity()) * sizeof(NodeId);
  }

  // The road nodes S's arcs lead to and G's arcs come from (sorted).
  [[nodiscard]] std::span<const NodeId> start_heads() const { return start_heads_; }
  [[nodiscard]] std::span<const NodeId> goal_tails() const { return goal_tails_; }

  // Consistent lower bounds on the cost from S to v (D* Lite's backward search) and from v to G
  // (A*'s forward search). Every path from S leaves through a start head, every path to G arrives
  // through a goal tail, and the arcs from S and to G cost at least 0, so the minimum of the
  // landmark bound over those nodes is admissible; a minimum of consistent bounds is consistent.
  [[nodiscard]] double h_from_start_s(Vertex v) const {
    if (!is_turn_vertex(v)) return 0.0;
    double best = kInfCost;
    for (NodeId a : start_heads_) best = std::min(best, cost_->lower_bound_s(a, node(v)));
    return best;
  }
  [[nodiscard]] double h_to_goal_s(Vertex v) const {
    if (!is_turn_vertex(v)) return 0.0;
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
  // drives on (for S and G arcs, the start or goal edge). Turns the vehicle may not make are left out.
  template <class F>
  void for_each_successor(Vertex u, F&& f) const {
    const auto& g = cost_->graph();
    if (u == start()) {
      for (const EdgePoint& s : starts_) {
        f(Vertex{s.vertex()}, cost_->partial_time_s(s.edge, s.offset_m, g.length_m(s.edge)), s.edge);
        for (const EdgePoint& t : goals_) {
          if (t.edge == s.edge && t.offset_m >= s.offset_m) f(goal(), cost_->partial_time_s(s.edge, s.offset_m, t.offset_m), s.edge);
        }
      }
      return;
    }
    if (u == goal()) return;
    const EdgeId in = edge(u);
    const bool at_goal_tail = std::binary_search(goal_tails_.begin(), goal_tails_.end(), cost_->graph().head(in));
    for (const maps::TurnArc& a : turns_->arcs_out(u.v)) {
      const Vertex v{a.other};
      const EdgeId onto = edge(v);
      const double turn = cost_->turn_cost_s(in, a, onto);
      if (turn >= kInfCost) continue;
      f(v, add_cost(turn, cost_->transit_s(onto)), onto);
      if (!at_goal_tail) continue;
      for (const EdgePoint& t : goals_) {
        if (t.edge == onto) f(goal(), add_cost(turn, goal_arc_s(t)), onto);
      }
    }
  }

  // f(Vertex from, double cost_s) for every arc into v.
  template <class F>
  void for_each_predecessor(Vertex v, F&& f) const {
    const auto& g = cost_->graph();
    if (v == start()) return;
    if (v == goal()) {
      for (const EdgePoint& t : goals_) {
        const double arc = goal_arc_s(t);
        auto from_turns_into = [&](std::uint32_t x) {
          for (const maps::TurnArc& a : turns_->arcs_in(x)) {
            const double turn = cost_->turn_cost_s(edge(Vertex{a.other}), a, t.edge);
            if (turn < kInfCost) f(Vertex{a.other}, add_cost(turn, arc));
          }
        };
        from_turns_into(t.edge.v);
        for (std::uint32_t c : turns_->copies_of(t.edge)) from_turns_into(c);
      }
      for (const EdgePoint& s : starts_) {
        for (const EdgePoint& t : goals_) {
          if (t.edge == s.edge && t.offset_m >= s.offset_m) f(start(), cost_->partial_time_s(s.edge, s.offset_m, t.offset_m));
        }
      }
      return;
    }
    const EdgeId e = edge(v);
    const double drive = cost_->transit_s(e);
    for (const maps::TurnArc& a : turns_->arcs_in(v.v)) {
      const double turn = cost_->turn_cost_s(edge(Vertex{a.other}), a, e);
      if (turn < kInfCost) f(Vertex{a.other}, add_cost(turn, drive));
    }
    for (const EdgePoint& s : starts_) {
      if (s.vertex() == v.v) f(start(), cost_->partial_time_s(s.edge, s.offset_m, g.length_m(s.edge)));
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
  const maps::TurnGraph* turns_;
  std::size_t turn_vertices_;
  std::vector<EdgePoint> starts_;
  std::vector<EdgePoint> goals_;
  std::vector<NodeId> start_heads_;
  std::vector<NodeId> goal_tails_;
  std::vector<NodeId> old_heads_;  // move_starts' scratch: the heads before the move
};

}  // namespace corridor::planner
