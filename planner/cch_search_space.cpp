#include "planner/cch_search_space.hpp"

#include <iterator>

#include "planner/gallop.hpp"

namespace corridor::planner {

CchSearchSpace::CchSearchSpace(const CchMetric& metric, std::vector<EdgePoint> starts, std::vector<EdgePoint> goals)
    : metric_(&metric),
      topology_(&metric.topology()),
      n_(metric.topology().vertex_count()),
      flat_(metric.cost(), std::move(starts), std::move(goals)) {
  const maps::TurnGraph& turns = topology_->turns();
  // G's arcs: every turn onto a goal edge, or onto one of its via-way copies, as SearchSpace has them.
  for (std::uint32_t i = 0; i < flat_.goals().size(); ++i) {
    const EdgeId e = flat_.goals()[i].edge;
    auto turns_into = [&](std::uint32_t v) {
      for (const maps::TurnArc& in : turns.arcs_in(v)) {
        for (const maps::TurnArc& out : turns.arcs_out(in.other)) {
          if (out.other != v) continue;
          targets_.push_back({topology_->rank(in.other), i, topology_->turn_arc_index(out)});
        }
      }
    };
    turns_into(e.v);
    for (std::uint32_t c : turns.copies_of(e)) turns_into(c);
  }
  std::sort(targets_.begin(), targets_.end(), [](const Target& a, const Target& b) { return a.rank < b.rank; });
  std::vector<std::uint32_t> from, members;
  for (const Target& t : targets_) from.push_back(t.rank);
  topology_->ancestors(from, members);
  build_half(std::move(members), false, down_set_, down_first_, down_arcs_);
  from.clear();
  for (const EdgePoint& s : flat_.starts()) from.push_back(topology_->rank(s.vertex()));
  std::sort(from.begin(), from.end());
  start_ranks_ = from;
  topology_->ancestors(from, members);
  build_half(std::move(members), true, up_set_, up_first_, up_arcs_);
}

void CchSearchSpace::build_half(std::vector<std::uint32_t> members, bool upward, std::vector<std::uint32_t>& set,
                                std::vector<std::uint32_t>& first, std::vector<CchDownArc>& arcs) const {
  set = std::move(members);
  const auto open_above = [&](std::uint32_t x) { return upward ? metric_->upper_out(x) : metric_->upper_in(x); };
  // Every higher neighbour of a member is a member (an ancestor of an ancestor). Both lists are
  // ascending, so each neighbour's place in the set is found by galloping on from the last one's.
  std::vector<std::uint32_t> slots;
  for (std::size_t i = 0; i < set.size(); ++i) {
    auto at = set.begin() + static_cast<std::ptrdiff_t>(i);
    for (const CchDownArc& a : open_above(set[i])) {
      at = gallop_to(at, set.end(), a.tail, [](std::uint32_t r) { return r; });
      slots.push_back(static_cast<std::uint32_t>(at - set.begin()));
    }
  }
  first.assign(set.size() + 1, 0);
  for (std::uint32_t at : slots) ++first[at + 1];
  for (std::size_t i = 1; i < first.size(); ++i) first[i] += first[i - 1];
  arcs.resize(first.back());
  std::vector<std::uint32_t> fill(first.begin(), first.end() - 1);
  std::size_t next = 0;
  for (std::uint32_t x : set) {
    for (const CchDownArc& a : open_above(x)) arcs[fill[slots[next++]]++] = {x, a.arc};
  }
}

double CchSearchSpace::move_starts(std::vector<EdgePoint> starts) {
  flat_.set_starts(std::move(starts));
  std::vector<std::uint32_t> from;
  for (const EdgePoint& s : flat_.starts()) from.push_back(topology_->rank(s.vertex()));
  std::sort(from.begin(), from.end());
  rewired_.clear();
  // Further along the same edges (most position reports): the same ancestors.
  if (from == start_ranks_) return 0.0;
  start_ranks_ = from;
  std::vector<std::uint32_t> members;
  topology_->ancestors(from, members);
  if (members == up_set_) return 0.0;  // along the same edge, or onto one with the same ancestors
  std::vector<std::uint32_t> old_set = std::move(up_set_);
  build_half(std::move(members), true, up_set_, up_first_, up_arcs_);
  // A vertex that joined or left the upward half gained or lost its upward arcs.
  std::vector<std::uint32_t> moved;
  std::set_symmetric_difference(old_set.begin(), old_set.end(), up_set_.begin(), up_set_.end(), std::back_inserter(moved));
  for (std::uint32_t r : moved) rewired_.push_back(Vertex{r});
  return 0.0;
}

void CchSearchSpace::vertices_on_arcs(std::span<const std::uint32_t> arcs, std::vector<Vertex>& out) const {
  out.clear();
  if (std::is_sorted(arcs.begin(), arcs.end())) {
    // Arc ids are grouped by their lower end: member x's arcs are [first_up(x), first_up(x + 1)).
    // Each half's members are ascending, so one forward pass over the batch serves each half.
    const auto scan = [&](const std::vector<std::uint32_t>& members, bool upward) {
      auto it = arcs.begin();
      for (std::uint32_t x : members) {
        const std::uint32_t lo = topology_->first_up(x);
        const std::uint32_t hi = topology_->first_up(x + 1);
        it = std::lower_bound(it, arcs.end(), lo);
        if (it == arcs.end()) return;
        for (; it != arcs.end() && *it < hi; ++it) {
          if (!metric_->open(*it, upward)) continue;  // not an arc of this half
          out.push_back(Vertex{upward ? x : topology_->head(*it)});
          if (upward) it = std::lower_bound(it, arcs.end(), hi) - 1;  // one of x's arcs is enough
        }
      }
    };
    scan(up_set_, true);
    scan(down_set_, false);
  } else {
    for (std::uint32_t arc : arcs) for_each_vertex_on_arc(arc, [&](Vertex u) { out.push_back(u); });
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
}

double CchSearchSpace::target_cost_s(const Target& t) const {
  const maps::TurnGraph& turns = topology_->turns();
  const EdgePoint& g = goals()[t.goal];
  const maps::TurnArc& a = topology_->turn_arc(t.turn);
  const double turn = cost().turn_cost_s(turns.edge_of(topology_->turn_arc_source(t.turn)), a, g.edge);
  if (turn >= kInfCost) return kInfCost;
  // As SearchSpace's goal arc: cross the goal edge's tail, then drive to the goal point.
  const double arrive = add_cost(cost().node_delay_s(cost().graph().tail(g.edge)), cost().partial_time_s(g.edge, 0.0, g.offset_m));
  return add_cost(turn, arrive);
}

Route CchSearchSpace::route_along(const std::vector<Via>& vias) const {
  std::vector<EdgeId> edges;
  std::vector<std::uint32_t> vertices;
  for (const Via& via : vias) {
    if (via.kind == Via::Kind::up || via.kind == Via::Kind::down) {
      vertices.clear();
      metric_->unpack(via.arc, via.kind == Via::Kind::up, vertices);
      for (std::uint32_t v : vertices) edges.push_back(topology_->turns().edge_of(v));
    } else {
      edges.push_back(via.edge);
    }
  }
  return flat_.route_along(std::move(edges));
}

std::size_t CchSearchSpace::heap_bytes() const {
  return flat_.heap_bytes() + (start_ranks_.capacity() + up_set_.capacity() + up_first_.capacity() + down_set_.capacity() + down_first_.capacity()) *
                             sizeof(std::uint32_t) +
         (up_arcs_.capacity() + down_arcs_.capacity()) * sizeof(CchDownArc) + targets_.capacity() * sizeof(Target) +
         rewired_.capacity() * sizeof(Vertex);
}

}  // namespace corridor::planner
