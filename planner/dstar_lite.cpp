#include "planner/dstar_lite.hpp"

#include <algorithm>
#include <cmath>

namespace corridor::planner {

template <class Space>
BasicDStarLite<Space>::BasicDStarLite(const typename Space::Source& source, std::vector<EdgePoint> starts,
                                      std::vector<EdgePoint> goals, DStarLiteOptions options)
    : space_(source, std::move(starts), std::move(goals)),
      options_(options),
      states_(std::make_unique<PagedVertexStates>(space_.vertex_count())),
      open_(PagedVertexStates::HeapPositions(states_.get())) {
  // Initialize(): the search runs backward, so it starts at the goal. (Koenig & Likhachev Fig. 4)
  const Vertex goal = space_.goal();
  states_->at(goal.v).rhs = 0.0;
  open_.push_or_update(goal.v, calculate_key(goal));
}

template <class Space>
typename BasicDStarLite<Space>::Key BasicDStarLite<Space>::calculate_key(Vertex s) const {
  const VertexState& st = states_->get(s.v);
  const double m = std::min(st.g, st.rhs);
  return {add_cost(add_cost(m, space_.h_from_start_s(s)), km_), m};
}

template <class Space>
double BasicDStarLite<Space>::min_successor_cost(Vertex u) const {
  double best = kInfCost;
  space_.for_each_successor(u, [&](Vertex v, double c, const Via&) { best = std::min(best, add_cost(c, g(v))); });
  return best;
}

template <class Space>
void BasicDStarLite<Space>::update_vertex(Vertex u, bool activate) {
  const double gu = g(u);
  const double ru = rhs(u);
  if (gu == ru) {
    open_.remove(u.v);
  } else if (ru < gu || !options_.lazy_raises || activate || u == space_.start() || open_.contains(u.v)) {
    // S is always queued when stale: the loop's own condition waits on it.
    open_.push_or_update(u.v, calculate_key(u));
  }
}

template <class Space>
void BasicDStarLite<Space>::recompute_rhs(Vertex u) {
  if (u == space_.goal()) return;
  const double best = min_successor_cost(u);
  // An untouched vertex whose rhs stays infinite keeps its page unallocated.
  if (best != rhs(u)) states_->at(u.v).rhs = best;
  update_vertex(u);
}

template <class Space>
void BasicDStarLite<Space>::move_start(std::vector<EdgePoint> starts) {
  // km grows by h(s_last, s_start) so that keys already queued stay lower bounds (paper line 38'').
  km_ = add_cost(km_, space_.move_starts(std::move(starts)));
  recompute_rhs(space_.start());
}

template <class Space>
void BasicDStarLite<Space>::edges_changed(std::span<const EdgeId> edges) {
  bool start_affected = false;
  for (EdgeId e : edges) {
    // On the turn graph, every arc whose cost can depend on e drives onto e (a turn onto e or one of
    // its copies, or a goal arc on e), and so starts at a vertex turning onto e; or it leaves S. On
    // a CCH that is the goal arcs and S; the shortcuts e enters arrive through arcs_changed.
    space_.for_each_vertex_turning_onto(e, [&](Vertex u) { recompute_rhs(u); });
    start_affected = start_affected || space_.is_start_edge(e);
  }
  if (start_affected) {
    // On a CCH, S's arcs are upward paths from the start edges: derived again first.
    if constexpr (std::is_same_v<Space, CchSearchSpace>) space_.refresh_start();
    recompute_rhs(space_.start());
  }
}

template <class Space>
void BasicDStarLite<Space>::arcs_changed(std::span<const std::uint32_t> arcs)
  requires std::is_same_v<Space, CchSearchSpace>
{
  // Near the top of the hierarchy a vertex has hundreds of arcs, and a batch changes many of them:
  // each vertex's rhs is re-derived once, not once per changed arc.
  // (`if constexpr` as well: clang instantiates this member for SearchSpace too, constraint or not.)
  if constexpr (std::is_same_v<Space, CchSearchSpace>) {
    std::vector<Vertex> touched;
    space_.arcs_changed(arcs, touched);
    for (Vertex u : touched) recompute_rhs(u);
  }
}

template <class Space>
void BasicDStarLite<Space>::nodes_changed(std::span<const NodeId> nodes) {
  // A node's crossing delay is part of every arc that turns at it: the arcs out of the vertices
  // standing there, and of no other arc.
  for (NodeId n : nodes) space_.for_each_vertex_at(n, [&](Vertex u) { recompute_rhs(u); });
}

template <class Space>
ReplanStats BasicDStarLite<Space>::replan() {
  ReplanStats stats;
  // A start whose every arc is closed reaches nothing, and a goal whose every arc is closed is
  // reached from nowhere, whatever the g values. The loop would settle the whole old search tree to
  // prove it (S's key is infinite); stop at once instead. The queue keeps its entries, so the next
  // replan carries on from a state that is still D* Lite's.
  const Vertex start = space_.start();
  bool start_cut_off = true;
  space_.for_each_successor(start, [&](Vertex, double c, const Via&) { start_cut_off = start_cut_off && c >= kInfCost; });
  bool goal_cut_off = true;
  space_.for_each_predecessor(space_.goal(), [&](Vertex, double c) { goal_cut_off = goal_cut_off && c >= kInfCost; });
  cut_off_ = start_cut_off || goal_cut_off;
  if (cut_off_) return stats;
  // Lazy raises (Delayed D*): settle what the start's key requires, then check the path the g values
  // give. A stale vertex on it is queued and the search goes on; a path consistent from end to end
  // costs exactly what rhs(S) says, and every vertex off it has a g that is a lower bound or a key
  // at or above S's, so no other path can be cheaper (docs/routing.md).
  do {
    compute_shortest_path(stats);
  } while (options_.lazy_raises && activate_stale_on_path(stats));
  return stats;
}

template <class Space>
void BasicDStarLite<Space>::compute_shortest_path(ReplanStats& stats) {
  const Vertex start = space_.start();
  const Vertex goal = space_.goal();
  // The paper stops once TopKey >= key(start). Here S's arcs can cost 0 (the vehicle exactly at a
  // node), so an underconsistent successor of S can tie with S's key, and a stale key summed in
  // another order (g + h(old, v) + km_old against g + km_new) can land an ulp above it. Processing
  // such near-ties is always safe, and stopping before them leaves S with a stale value.
  auto must_continue = [&] {
    const Key ks = calculate_key(start);
    const double slack = 1e-9 * std::max(1.0, std::abs(ks.k1));
    return open_.top_key().k1 <= ks.k1 + slack || rhs(start) > g(start);
  };
  while (!open_.empty() && must_continue()) {
    const Vertex u{open_.top()};
    const Key k_old = open_.top_key();
    const Key k_new = calculate_key(u);
    ++stats.expanded;
    if (k_old < k_new) {
      ++stats.rekeyed;
      open_.push_or_update(u.v, k_new);
    } else if (g(u) > rhs(u)) {
      // Overconsistent: settle u and relax its predecessors.
      VertexState& su = states_->at(u.v);
      su.g = su.rhs;
      const double gu = su.g;
      open_.remove(u.v);
      space_.for_each_predecessor(u, [&](Vertex s, double c) {
        if (s == goal) return;
        const double via_u = add_cost(c, gu);
        if (via_u < rhs(s)) {
          states_->at(s.v).rhs = via_u;
          update_vertex(s);
          ++stats.updated;
        }
      });
    } else {
      // Underconsistent: u's old value may have supported its predecessors; re-derive them.
      ++stats.underconsistent;
      const double g_old = g(u);
      states_->at(u.v).g = kInfCost;
      space_.for_each_predecessor(u, [&](Vertex s, double c) {
        // Only a predecessor that u supported changes. The others keep g, rhs and so their place
        // in (or out of) the queue; a key left stale is a lower bound, which the rekey step handles.
        if (s != goal && rhs(s) == add_cost(c, g_old)) {
          states_->at(s.v).rhs = min_successor_cost(s);
          ++stats.updated;
          // A raise, once started, runs through everything it supported, lazy or not. Left waiting,
          // the vertices u supported would re-derive their values from each other's stale ones and
          // climb by one arc's cost per round (counting to infinity around a closed-off area).
          update_vertex(s, true);
        }
      });
      // rhs(u) depends only on u's successors, which did not change: it stays valid.
      update_vertex(u);
    }
  }
}

template <class Space>
bool BasicDStarLite<Space>::activate_stale_on_path(ReplanStats& stats) {
  ++stats.path_checks;
  const Vertex start = space_.start();
  const Vertex goal = space_.goal();
  if (rhs(start) > g(start)) {
    update_vertex(start, true);
    ++stats.activated;
    return true;
  }
  if (rhs(start) >= kInfCost) return false;
  Vertex u = start;
  // Along consistent vertices g falls strictly (every arc but S's costs more than 0), so the walk
  // reaches G or a stale vertex within vertex_count steps.
  for (std::size_t steps = 0; u != goal && steps < space_.vertex_count(); ++steps) {
    double best = kInfCost;
    Vertex next;
    space_.for_each_successor(u, [&](Vertex v, double c, const Via&) {
      const double total = add_cost(c, v == goal ? 0.0 : g(v));
      if (total < best) {
        best = total;
        next = v;
      }
    });
    if (!next.valid() || next == goal) return false;
    const VertexState& sn = states_->get(next.v);
    if (sn.g < sn.rhs) {
      update_vertex(next, true);
      ++stats.activated;
      return true;
    }
    // An overconsistent vertex on the path has a key at S's (within rounding), as in the paper's
    // own termination; the path through it is the one the eager search would also return.
    if (sn.g > sn.rhs) return false;
    u = next;
  }
  return false;
}

template <class Space>
std::string BasicDStarLite<Space>::invariant_violation() const {
  for (std::uint32_t i = 0; i < space_.vertex_count(); ++i) {
    const Vertex u{i};
    const double expected_rhs = u == space_.goal() ? 0.0 : min_successor_cost(u);
    if (expected_rhs != rhs(u)) {
      return "vertex " + std::to_string(i) + ": rhs " + std::to_string(rhs(u)) + " but successors give " +
             std::to_string(expected_rhs);
    }
    const bool queued = open_.contains(i);
    // Lazy raises leave stale vertices off the queue, but never a stale S (the loop waits on it).
    const bool must_queue = options_.lazy_raises ? rhs(u) < g(u) || (u == space_.start() && g(u) != rhs(u)) : g(u) != rhs(u);
    const bool may_queue = g(u) != rhs(u);
    if ((must_queue && !queued) || (queued && !may_queue)) {
      return "vertex " + std::to_string(i) + ": queued=" + std::to_string(open_.contains(i)) + " g=" +
             std::to_string(g(u)) + " rhs=" + std::to_string(rhs(u));
    }
  }
  return {};
}

template <class Space>
std::size_t BasicDStarLite<Space>::memory_bytes() const {
  return sizeof(*this) + states_->bytes() + open_.capacity_bytes() + space_.heap_bytes();
}

template <class Space>
std::vector<typename BasicDStarLite<Space>::Via> BasicDStarLite<Space>::path() const {
  const Vertex start = space_.start();
  const Vertex goal = space_.goal();
  if (cost_to_goal_s() >= kInfCost) return {};
  std::vector<Via> vias;
  Vertex u = start;
  // Every arc costs more than zero except S arcs, so a path has at most max_path_arcs arcs; a walk
  // over stale values (before replan()) may circle, and stops there.
  for (std::size_t steps = 0; u != goal && steps < space_.max_path_arcs(); ++steps) {
    double best = kInfCost;
    Vertex next;
    Via via{};
    space_.for_each_successor(u, [&](Vertex v, double c, const Via& e) {
      const double total = add_cost(c, v == goal ? 0.0 : g(v));
      if (total < best) {
        best = total;
        next = v;
        via = e;
      }
    });
    if (!next.valid()) return {};
    vias.push_back(via);
    u = next;
  }
  if (u != goal) vias.clear();
  return vias;
}

template class BasicDStarLite<SearchSpace>;
template class BasicDStarLite<CchSearchSpace>;

}  // namespace corridor::planner
