// One mission's search graph on a customizable contraction hierarchy: the arcs an upward search
// from the start and a downward search to the goal can use, with the virtual start S and goal G of
// SearchSpace. S, and every vertex of the upward half, reaches G at its true cost over the turn
// graph (at a lower bound of it, on a metric with lazy rises: planner/settled_replan.hpp): a
// cheapest path goes up from the start through the elimination tree's ancestors of the start, then
// down through those of the goal (Dibbelt, Strasser & Wagner 2016, §6). Other vertices' values are
// upper bounds at best: only cost_to_goal and the route are meaningful. This is D* Lite's graph at
// metro scale: a few thousand vertices around two elimination-tree paths instead of the whole
// city.
//
// Vertices are CCH ranks (planner/cch_topology.hpp), then S, then G. The arcs:
//   S → the start points' vertices (the rest of the start edge), and S → G on one edge;
//   x → y for every CCH arc with x below y, x an ancestor of a start vertex and x→y open for the
//   profile (planner/cch_metric.hpp; weight x→y);
//   y → x for every CCH arc with x below y, x an ancestor of a goal vertex and y→x open (weight y→x);
//   x → G for every turn onto a goal edge from x (the turn, then the goal edge up to the goal).
// When the vehicle moves, the start's ancestors change: move_starts reports the vertices whose
// arcs came or went, and D* Lite repairs them like any cost change.
#pragma once

#include <algorithm>
#include <span>
#include <vector>

#include "planner/cch_metric.hpp"
#include "planner/search_space.hpp"

namespace corridor::planner {

// The arc a route takes out of a vertex: from S onto a start edge, up or down a CCH arc (to be
// unpacked), onto the goal edge into G, or S to G along one edge.
struct CchVia {
  enum class Kind : std::uint8_t { start, up, down, goal, direct };
  Kind kind = Kind::start;
  std::uint32_t arc = kNoCchArc;
  EdgeId edge;
};

class CchSearchSpace {
 public:
  using Via = CchVia;
  using Source = CchMetric;

  // Throws std::invalid_argument as SearchSpace does.
  CchSearchSpace(const CchMetric& metric, std::vector<EdgePoint> starts, std::vector<EdgePoint> goals);

  [[nodiscard]] std::size_t vertex_count() const { return n_ + 2; }
  // The most arcs a path from S to G can take without visiting a vertex twice: S, the two halves,
  // G. A greedy walk over stale values that goes on longer is going round in circles.
  [[nodiscard]] std::size_t max_path_arcs() const { return up_set_.size() + down_set_.size() + 2; }
  [[nodiscard]] Vertex start() const { return Vertex{static_cast<std::uint32_t>(n_)}; }
  [[nodiscard]] Vertex goal() const { return Vertex{static_cast<std::uint32_t>(n_ + 1)}; }
  // No heuristic: the graph is small, and the key modifier never moves.
  [[nodiscard]] double h_from_start_s(Vertex) const { return 0.0; }

  // The vehicle moved: S's arcs change, and so does the upward half of the graph. Returns the
  // key modifier's increase (0 without a heuristic); rewired() then lists the vertices whose
  // arcs came or went.
  double move_starts(std::vector<EdgePoint> starts);
  [[nodiscard]] std::span<const Vertex> rewired() const { return rewired_; }

  [[nodiscard]] const CchMetric& metric() const { return *metric_; }
  [[nodiscard]] std::span<const EdgePoint> starts() const { return flat_.starts(); }
  [[nodiscard]] std::span<const EdgePoint> goals() const { return flat_.goals(); }
  [[nodiscard]] bool is_start_edge(EdgeId e) const { return flat_.is_start_edge(e); }
  // The vertices whose arcs an edge's conditions enter directly: the turns into G over a goal
  // edge (the CCH arcs change through the metric: for_each_vertex_on_arc).
  template <class F>
  void for_each_vertex_turning_onto(EdgeId e, F&& f) const {
    for (const Target& t : targets_) {
      if (goals()[t.goal].edge == e) f(Vertex{t.rank});
    }
  }
  // The same for a node's delays: the turns into G made at the goal edge's tail.
  template <class F>
  void for_each_vertex_at(NodeId n, F&& f) const {
    for (const Target& t : targets_) {
      if (metric_->cost().graph().tail(goals()[t.goal].edge) == n) f(Vertex{t.rank});
    }
  }
  // The vertices whose arcs use CCH arc `arc` (whose weight the metric changed).
  template <class F>
  void for_each_vertex_on_arc(std::uint32_t arc, F&& f) const {
    const std::uint32_t x = topology_->tail(arc);
    if (metric_->open(arc, true) && in_up(x)) f(Vertex{x});
    if (metric_->open(arc, false) && in_down(x)) f(Vertex{topology_->head(arc)});
  }
  // The same for a batch of arcs, each vertex once, in ascending order, into `out` (cleared). A
  // batch sorted by id (as the metric hands them out) is read only where the mission's vertices'
  // arcs lie: a city-wide batch holds thousands of arcs, a mission's graph a few hundred vertices.
  void vertices_on_arcs(std::span<const std::uint32_t> arcs, std::vector<Vertex>& out) const;

  // f(Vertex to, double cost_s, Via via) for every arc out of u.
  template <class F>
  void for_each_successor(Vertex u, F&& f) const {
    if (u == start()) {
      for (const EdgePoint& s : starts()) {
        f(Vertex{topology_->rank(s.vertex())}, cost().partial_time_s(s.edge, s.offset_m, length_m(s.edge)),
          Via{Via::Kind::start, kNoCchArc, s.edge});
      }
      for_each_direct([&](double c, EdgeId e) { f(goal(), c, Via{Via::Kind::direct, kNoCchArc, e}); });
      return;
    }
    if (u == goal()) return;
    const std::uint32_t r = u.v;
    if (in_up(r)) {
      for (const CchDownArc& a : metric_->upper_out(r)) f(Vertex{a.tail}, metric_->up_s(a.arc), Via{Via::Kind::up, a.arc, EdgeId{}});
    }
    for (const CchDownArc& d : down_out(r)) f(Vertex{d.tail}, metric_->down_s(d.arc), Via{Via::Kind::down, d.arc, EdgeId{}});
    for_each_target_arc(r, [&](double c, EdgeId e) { f(goal(), c, Via{Via::Kind::goal, kNoCchArc, e}); });
  }

  // f(Vertex from, double cost_s) for every arc into v.
  template <class F>
  void for_each_predecessor(Vertex v, F&& f) const {
    if (v == start()) return;
    if (v == goal()) {
      for (const Target& t : targets_) f(Vertex{t.rank}, target_cost_s(t));
      for_each_direct([&](double c, EdgeId) { f(start(), c); });
      return;
    }
    const std::uint32_t r = v.v;
    for (const CchDownArc& d : up_in(r)) f(Vertex{d.tail}, metric_->up_s(d.arc));
    if (in_down(r)) {
      for (const CchDownArc& a : metric_->upper_in(r)) f(Vertex{a.tail}, metric_->down_s(a.arc));
    }
    for (const EdgePoint& s : starts()) {
      if (topology_->rank(s.vertex()) == r) f(start(), cost().partial_time_s(s.edge, s.offset_m, length_m(s.edge)));
    }
  }

  // The route along these arcs from S to G, shortcuts unpacked into the turns they stand for.
  [[nodiscard]] Route route_along(const std::vector<Via>& vias) const;

  // How many vertices the two halves hold, and the bytes the mission's copy of them holds on the
  // heap.
  [[nodiscard]] std::size_t upward_size() const { return up_set_.size(); }
  [[nodiscard]] std::size_t downward_size() const { return down_set_.size(); }
  [[nodiscard]] std::size_t heap_bytes() const;

 private:
  // A turn into G: from `rank` onto goals()[goal].edge by turn-graph arc `turn` (an index into the
  // turn graph's out-arcs).
  struct Target {
    std::uint32_t rank;
    std::uint32_t goal;
    std::uint32_t turn;
  };
  [[nodiscard]] const TravelCost& cost() const { return metric_->cost(); }
  [[nodiscard]] double length_m(EdgeId e) const { return metric_->cost().graph().length_m(e); }
  [[nodiscard]] bool in_up(std::uint32_t r) const { return std::binary_search(up_set_.begin(), up_set_.end(), r); }
  [[nodiscard]] bool in_down(std::uint32_t r) const {
    return std::binary_search(down_set_.begin(), down_set_.end(), r);
  }
  // Upward arcs into r from the members below it (r in the upward half), downward arcs out of r
  // to the members below it (r in the downward half); empty when r is not in that half.
  [[nodiscard]] std::span<const CchDownArc> up_in(std::uint32_t r) const {
    return filed_under(r, up_set_, up_first_, up_arcs_);
  }
  [[nodiscard]] std::span<const CchDownArc> down_out(std::uint32_t r) const {
    return filed_under(r, down_set_, down_first_, down_arcs_);
  }
  static std::span<const CchDownArc> filed_under(std::uint32_t r, const std::vector<std::uint32_t>& set,
                                                 const std::vector<std::uint32_t>& first,
                                                 const std::vector<CchDownArc>& arcs) {
    const auto it = std::lower_bound(set.begin(), set.end(), r);
    if (it == set.end() || *it != r) return {};
    const auto i = static_cast<std::size_t>(it - set.begin());
    return {arcs.data() + first[i], first[i + 1] - first[i]};
  }
  [[nodiscard]] double target_cost_s(const Target& t) const;
  template <class F>
  void for_each_target_arc(std::uint32_t r, F&& f) const {
    auto it = std::lower_bound(targets_.begin(), targets_.end(), r, [](const Target& t, std::uint32_t x) { return t.rank < x; });
    for (; it != targets_.end() && it->rank == r; ++it) f(target_cost_s(*it), goals()[it->goal].edge);
  }
  template <class F>
  void for_each_direct(F&& f) const {
    for (const EdgePoint& s : starts()) {
      for (const EdgePoint& t : goals()) {
        if (t.edge == s.edge && t.offset_m >= s.offset_m) f(cost().partial_time_s(s.edge, s.offset_m, t.offset_m), s.edge);
      }
    }
  }
  // Builds a half from its members (the ancestors of its vertices, ascending), filing the arcs
  // between members under their higher end (the upward half enters it by them, the downward half
  // leaves by them). Only arcs open in the half's direction are filed.
  void build_half(std::vector<std::uint32_t> members, bool upward, std::vector<std::uint32_t>& set,
                  std::vector<std::uint32_t>& first, std::vector<CchDownArc>& arcs) const;

  const CchMetric* metric_;
  const CchTopology* topology_;
  std::size_t n_;
  SearchSpace flat_;  // the starts and goals, checked and clamped, and the route builder
  std::vector<Target> targets_;  // by rank
  std::vector<std::uint32_t> start_ranks_;  // the start vertices' ranks, ascending: the upward half's seeds
  std::vector<std::uint32_t> up_set_, up_first_;
  std::vector<CchDownArc> up_arcs_;
  std::vector<std::uint32_t> down_set_, down_first_;
  std::vector<CchDownArc> down_arcs_;
  std::vector<Vertex> rewired_;
};

}  // namespace corridor::planner
