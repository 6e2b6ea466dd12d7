// One mission's search graph on a customizable contraction hierarchy, with the virtual start S and
// goal G of SearchSpace. A cheapest path over the turn graph goes up from the start through the
// elimination tree's ancestors of the start (the upward half), then down through those of the
// goal (the downward half), meeting at a vertex of both (Dibbelt, Strasser & Wagner 2016, §6).
// This is D* Lite's graph at metro scale: a few hundred vertices around the goal's elimination-tree
// path instead of the whole city.
//
// The goal never moves, so D* Lite keeps its backward tree over the downward half and repairs it
// as costs change. The start moves with the vehicle and takes a new upward half whenever it
// crosses into a new subtree, so the upward half is not part of D* Lite's graph: S's arcs are
// the cheapest upward paths from the start to each meeting vertex, found by one sweep up the
// half in rank order (its arcs all point up, so each vertex is final before it is read). On Porto
// a raise near the top of the upward half re-derived most of it through D* Lite's raise
// cascade, twice per vertex and with every successor read each time; the sweep reads each arc
// once (docs/routing.md). S and every vertex of the downward half reach G at their true cost
// (on a metric with lazy rises, a lower bound of it: planner/settled_replan.hpp); only
// cost_to_goal and the route are meaningful.
//
// Vertices are CCH ranks (planner/cch_topology.hpp), then S, then G. The arcs:
//   S → m for every meeting vertex m (in both halves) that an upward path reaches, and S → G on
//   one edge;
//   y → x for every CCH arc with x below y, x an ancestor of a goal vertex and y→x open (weight y→x);
//   x → G for every turn onto a goal edge from x (the turn, then the goal edge up to the goal).
// S's arcs change when the vehicle moves, its start edge's conditions change (refresh_start), or
// an arc of the upward half changes weight (arcs_changed); D* Lite re-derives S like any vertex
// whose arcs changed.
#pragma once

#include <algorithm>
#include <span>
#include <vector>

#include "planner/cch_metric.hpp"
#include "planner/search_space.hpp"

namespace corridor::planner {

// The arc a route takes out of a vertex: from S along a start edge and up the upward half to a
// meeting vertex, down a CCH arc (to be unpacked), onto the goal edge into G, or S to G along one
// edge.
struct CchVia {
  enum class Kind : std::uint8_t { start, down, goal, direct };
  Kind kind = Kind::start;
  // down: the CCH arc. start: the meeting vertex's place in the upward half (the path up to it,
  // start edge included, is the sweep's: CchSearchSpace::for_each_hierarchy_arc, route_along).
  std::uint32_t arc = kNoCchArc;
  EdgeId edge;  // goal, direct: the edge
};

class CchSearchSpace {
 public:
  using Via = CchVia;
  using Source = CchMetric;

  // Throws std::invalid_argument as SearchSpace does.
  CchSearchSpace(const CchMetric& metric, std::vector<EdgePoint> starts, std::vector<EdgePoint> goals);

  [[nodiscard]] std::size_t vertex_count() const { return n_ + 2; }
  // The most arcs a path from S to G can take without visiting a vertex twice: S's, the downward
  // half, G's. A greedy walk over stale values that goes on longer is going round in circles.
  [[nodiscard]] std::size_t max_path_arcs() const { return down_set_.size() + 2; }
  [[nodiscard]] Vertex start() const { return Vertex{static_cast<std::uint32_t>(n_)}; }
  [[nodiscard]] Vertex goal() const { return Vertex{static_cast<std::uint32_t>(n_ + 1)}; }
  // No heuristic: the graph is small, and the key modifier never moves.
  [[nodiscard]] double h_from_start_s(Vertex) const { return 0.0; }

  // The vehicle moved: a new upward half where it crossed into another subtree, and new costs of
  // S's arcs in any case. Returns the key modifier's increase (0 without a heuristic).
  double move_starts(std::vector<EdgePoint> starts);
  // A start edge's conditions changed: S's arcs cost what the start edges cost today.
  void refresh_start();

  [[nodiscard]] const CchMetric& metric() const { return *metric_; }
  [[nodiscard]] std::span<const EdgePoint> starts() const { return flat_.starts(); }
  [[nodiscard]] std::span<const EdgePoint> goals() const { return flat_.goals(); }
  [[nodiscard]] bool is_start_edge(EdgeId e) const { return flat_.is_start_edge(e); }
  // The vertices whose arcs an edge's conditions enter directly: the turns into G over a goal
  // edge (the CCH arcs change through the metric: arcs_changed).
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
  // The vertices whose arcs can use a batch of CCH arcs, each once,
  // in ascending order, into `out` (cleared): the downward half's vertices above an arc of the
  // batch, and S when an arc of the upward half is in it. A batch sorted by id (as the metric
  // hands them out) is read only where the mission's vertices' arcs lie: a city-wide batch holds
  // thousands of arcs, a mission's graph a few hundred vertices.
  void vertices_on_arcs(std::span<const std::uint32_t> arcs, std::vector<Vertex>& out) const;
  // The metric changed these arcs' weights: takes the upward half's new weights, derives S's arcs
  // again where they moved, and lists the vertices whose arcs changed as vertices_on_arcs does
  // (S only where an upward weight moved).
  void arcs_changed(std::span<const std::uint32_t> arcs, std::vector<Vertex>& out);

  // f(Vertex to, double cost_s, Via via) for every arc out of u.
  template <class F>
  void for_each_successor(Vertex u, F&& f) const {
    if (u == start()) {
      for (const Meeting& m : meetings_) {
        const double c = add_cost(start_shift_s_, up_cost_[m.place]);
        if (c < kInfCost) f(Vertex{m.rank}, c, Via{Via::Kind::start, m.place, EdgeId{}});
      }
      for_each_direct([&](double c, EdgeId e) { f(goal(), c, Via{Via::Kind::direct, kNoCchArc, e}); });
      return;
    }
    if (u == goal()) return;
    const std::uint32_t r = u.v;
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
    if (!in_down(r)) return;
    for (const CchDownArc& a : metric_->upper_in(r)) f(Vertex{a.tail}, metric_->down_s(a.arc));
    const auto m = std::lower_bound(meetings_.begin(), meetings_.end(), r,
                                    [](const Meeting& x, std::uint32_t rank) { return x.rank < rank; });
    if (m != meetings_.end() && m->rank == r) {
      const double c = add_cost(start_shift_s_, up_cost_[m->place]);
      if (c < kInfCost) f(start(), c);
    }
  }

  // f(arc, upward) for every hierarchy arc a route takes along `via`: a down arc, or the upward
  // path of a start via (in any order).
  template <class F>
  void for_each_hierarchy_arc(const Via& via, F&& f) const {
    if (via.kind == Via::Kind::down) f(via.arc, false);
    if (via.kind != Via::Kind::start) return;
    for (Step s = up_step_[via.arc]; s.from != kNoCchArc; s = up_step_[s.from]) f(s.arc, true);
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
  // A vertex of both halves: S's arcs end there.
  struct Meeting {
    std::uint32_t rank;
    std::uint32_t place;  // in the upward half
  };
  // An arc of the upward half, filed under its higher end: its lower end's place, and its id.
  struct UpArc {
    std::uint32_t tail_place;
    std::uint32_t arc;
  };
  // How the sweep reached a vertex of the upward half: by `arc` from the vertex at place `from`,
  // or (from = kNoCchArc) from S along start point `arc`.
  struct Step {
    std::uint32_t from = kNoCchArc;
    std::uint32_t arc = kNoCchArc;
  };
  // A start point's vertex: its place in the upward half, and what the sweep starts it at (the
  // start edge's rest; 0 for a single start point, whose cost is start_shift_s_).
  struct Seed {
    std::uint32_t place;
    std::uint32_t start;  // index into starts()
    double cost_s;
  };
  [[nodiscard]] const TravelCost& cost() const { return metric_->cost(); }
  [[nodiscard]] double length_m(EdgeId e) const { return metric_->cost().graph().length_m(e); }
  [[nodiscard]] bool in_down(std::uint32_t r) const {
    return std::binary_search(down_set_.begin(), down_set_.end(), r);
  }
  // Downward arcs out of r to the members below it (r in the downward half); empty otherwise.
  [[nodiscard]] std::span<const CchDownArc> down_out(std::uint32_t r) const {
    const auto it = std::lower_bound(down_set_.begin(), down_set_.end(), r);
    if (it == down_set_.end() || *it != r) return {};
    const auto i = static_cast<std::size_t>(it - down_set_.begin());
    return {down_arcs_.data() + down_first_[i], down_first_[i + 1] - down_first_[i]};
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
  // The downward half from its members (the goal vertices' ancestors, ascending): the arcs between
  // members open downward, filed under their higher end, which leaves by them.
  void build_down(std::vector<std::uint32_t> members);
  // The upward half from its members (the start vertices' ancestors, ascending): the arcs between
  // members open upward, filed under their higher end, with their weights; and the meeting
  // vertices. The top `shared` members are the top of the half held now (the vehicle moved into
  // another subtree of the same ancestors: on Porto a new start shares all but about 10 of its 240
  // ancestors): the arcs among them, their weights as last reported, and their slots are carried
  // over, and only the other members' arcs are read from the metric, whose scattered lists made a
  // move cost 0.27 ms in the slowest replans. The weights carried over are the metric's because
  // every change of it is reported (arcs_changed), as D* Lite needs anyway.
  void build_up(std::vector<std::uint32_t> members, std::size_t shared);
  // The start vertices' ancestors, ascending, into `out`: each start climbs the elimination tree
  // only until it meets the half held now, whose members' parents are kept (up_parent_), so that
  // a move reads the tree's scattered parent links only below the shared top. The count of
  // members at the top that the half held now shares is returned.
  std::size_t ancestors_of_starts(std::span<const std::uint32_t> from, std::vector<std::uint32_t>& out) const;
  // Fills up_range_ and up_parent_ for the members at places [from, to) from the topology.
  void describe_up_members(std::size_t from, std::size_t to);
  // The meeting vertices (members of both halves), and the sweep's state cleared, once the upward
  // half is built.
  void find_meetings();
  // The start points' costs today. One start point seeds the sweep at 0, and its cost is added to
  // S's arcs (start_shift_s_), so that driving along the edge moves no sweep; several seed it
  // at their costs. True when the sweep must run again.
  bool seed();
  // Derives the cheapest upward paths again from place `from` up: the vertices below it kept
  // theirs, as no arc into them changed.
  void sweep(std::size_t from);
  // Appends the upward arcs of the sweep's path to the vertex at `place` to `out`, from there
  // down; returns the start point the path leaves S by.
  std::uint32_t climb(std::uint32_t place, std::vector<std::uint32_t>& out) const;
  // on_up_arc(arc, place, slot) for every arc of the batch open upward in the upward half: its
  // lower end's place and its index in up_arcs_; and out gets the downward half's vertices above
  // an arc of the batch (unsorted, repeated).
  template <class F>
  void scan_batch(std::span<const std::uint32_t> arcs, std::vector<Vertex>& out, F&& on_up_arc) const;

  const CchMetric* metric_;
  const CchTopology* topology_;
  std::size_t n_;
  SearchSpace flat_;  // the starts and goals, checked and clamped, and the route builder
  std::vector<Target> targets_;  // by rank
  std::vector<std::uint32_t> start_ranks_;  // the start vertices' ranks, ascending: the upward half's seeds
  std::vector<std::uint32_t> down_set_, down_first_;
  std::vector<CchDownArc> down_arcs_;
  // Each member's arc ids (topology_->first_up(x) to first_up(x + 1)), beside the member lists:
  // a batch is matched against them without reading the topology at the members' scattered ranks.
  struct ArcRange {
    std::uint32_t first;
    std::uint32_t end;
  };
  std::vector<ArcRange> down_range_, up_range_;
  // Each upward member's parent in the elimination tree, as its place in up_set_ (kNoCchArc at a
  // root).
  std::vector<std::uint32_t> up_parent_;
  std::vector<std::uint32_t> up_set_, up_first_;
  std::vector<UpArc> up_arcs_;
  // The metric's weights of up_arcs_, as last reported (arcs_changed): the sweep reads them side
  // by side instead of scattered over the metric.
  std::vector<double> up_weight_s_;
  // Where each member's open upward arcs (metric_->upper_out, in its order) were filed in
  // up_arcs_: up_slot_[up_out_first_[place] + j] for the j-th. A congestion batch in the server
  // moves thousands of arcs of the hierarchy's top, which every mission's upward half holds; with
  // this a moved arc's copied weight is found by walking the member's list along the batch,
  // where two binary searches per arc (its head's place, then the arc among the head's) took 15 %
  // of bench serve's CPU.
  std::vector<std::uint32_t> up_slot_, up_out_first_;
  std::vector<Meeting> meetings_;  // by rank
  std::vector<Seed> seeds_;
  double start_shift_s_ = 0.0;  // added to every S arc (one start point: its cost)
  // The sweep: the cheapest upward path's cost from the seeds to each vertex of the upward half,
  // and its last step.
  std::vector<double> up_cost_;
  std::vector<Step> up_step_;
  // build_up's new arrays, swapped with the ones above when done (kept, so that a move does not
  // allocate the half's arrays again), and where each old slot went.
  struct UpArrays {
    std::vector<std::uint32_t> first, slot, out_first, parent, fill;
    std::vector<UpArc> arcs;
    std::vector<double> weight_s;
    std::vector<ArcRange> range;
  };
  UpArrays spare_;
  std::vector<std::uint32_t> moved_slot_;
  std::vector<std::uint32_t> heads_;  // the builds' scratch: each new arc's head place
};

}  // namespace corridor::planner
