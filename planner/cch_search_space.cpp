#include "planner/cch_search_space.hpp"

#include <cassert>

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
  build_down(std::move(members));
  from.clear();
  for (const EdgePoint& s : flat_.starts()) from.push_back(topology_->rank(s.vertex()));
  std::sort(from.begin(), from.end());
  start_ranks_ = from;
  members.clear();
  topology_->ancestors(from, members);
  build_up(std::move(members));
  (void)seed();
  sweep(0);
}

void CchSearchSpace::build_down(std::vector<std::uint32_t> members) {
  down_set_ = std::move(members);
  // Every higher neighbour of a member is a member (an ancestor of an ancestor). Both lists are
  // ascending, so each neighbour's place in the set is found by galloping on from the last one's.
  std::vector<std::uint32_t> slots;
  for (std::size_t i = 0; i < down_set_.size(); ++i) {
    auto at = down_set_.begin() + static_cast<std::ptrdiff_t>(i);
    for (const CchDownArc& a : metric_->upper_in(down_set_[i])) {
      at = gallop_to(at, down_set_.end(), a.tail, [](std::uint32_t r) { return r; });
      slots.push_back(static_cast<std::uint32_t>(at - down_set_.begin()));
    }
  }
  down_first_.assign(down_set_.size() + 1, 0);
  for (std::uint32_t at : slots) ++down_first_[at + 1];
  for (std::size_t i = 1; i < down_first_.size(); ++i) down_first_[i] += down_first_[i - 1];
  down_arcs_.resize(down_first_.back());
  std::vector<std::uint32_t> fill(down_first_.begin(), down_first_.end() - 1);
  std::size_t next = 0;
  for (std::uint32_t x : down_set_) {
    for (const CchDownArc& a : metric_->upper_in(x)) down_arcs_[fill[slots[next++]]++] = {x, a.arc};
  }
}

void CchSearchSpace::build_up(std::vector<std::uint32_t> members) {
  up_set_ = std::move(members);
  // Filed under the higher end, as the sweep reads them; each list ascends by lower end, and so
  // by arc id (ids ascend by lower end).
  std::vector<std::uint32_t> heads;
  up_first_.assign(up_set_.size() + 1, 0);
  for (std::size_t i = 0; i < up_set_.size(); ++i) {
    auto at = up_set_.begin() + static_cast<std::ptrdiff_t>(i);
    for (const CchDownArc& a : metric_->upper_out(up_set_[i])) {
      at = gallop_to(at, up_set_.end(), a.tail, [](std::uint32_t r) { return r; });
      heads.push_back(static_cast<std::uint32_t>(at - up_set_.begin()));
      ++up_first_[heads.back() + 1];
    }
  }
  for (std::size_t i = 1; i < up_first_.size(); ++i) up_first_[i] += up_first_[i - 1];
  up_arcs_.resize(up_first_.back());
  up_weight_s_.resize(up_first_.back());
  std::vector<std::uint32_t> fill(up_first_.begin(), up_first_.end() - 1);
  up_slot_.resize(heads.size());
  up_out_first_.resize(up_set_.size() + 1);
  std::uint32_t next = 0;
  for (std::uint32_t i = 0; i < up_set_.size(); ++i) {
    up_out_first_[i] = next;
    for (const CchDownArc& a : metric_->upper_out(up_set_[i])) {
      const std::uint32_t k = fill[heads[next]]++;
      up_slot_[next++] = k;
      up_arcs_[k] = {i, a.arc};
      up_weight_s_[k] = metric_->up_s(a.arc);
    }
  }
  up_out_first_[up_set_.size()] = next;
  meetings_.clear();
  auto d = down_set_.begin();
  for (std::uint32_t i = 0; i < up_set_.size(); ++i) {
    d = std::lower_bound(d, down_set_.end(), up_set_[i]);
    if (d == down_set_.end()) break;
    if (*d == up_set_[i]) meetings_.push_back({up_set_[i], i});
  }
  up_cost_.assign(up_set_.size(), kInfCost);
  up_step_.assign(up_set_.size(), Step{});
  seeds_.clear();
}

bool CchSearchSpace::seed() {
  std::vector<Seed> seeds;
  const auto starts = flat_.starts();
  for (std::uint32_t s = 0; s < starts.size(); ++s) {
    const EdgePoint& p = starts[s];
    const auto at = std::lower_bound(up_set_.begin(), up_set_.end(), topology_->rank(p.vertex()));
    seeds.push_back({static_cast<std::uint32_t>(at - up_set_.begin()), s, cost().partial_time_s(p.edge, p.offset_m, length_m(p.edge))});
  }
  const bool one = seeds.size() == 1;
  start_shift_s_ = one ? seeds[0].cost_s : 0.0;
  if (one) seeds[0].cost_s = 0.0;
  const bool same = seeds.size() == seeds_.size() && std::equal(seeds.begin(), seeds.end(), seeds_.begin(), [](const Seed& a, const Seed& b) {
                      return a.place == b.place && a.start == b.start && a.cost_s == b.cost_s;
                    });
  seeds_ = std::move(seeds);
  return !same;
}

void CchSearchSpace::sweep(std::size_t from) {
  std::fill(up_cost_.begin() + static_cast<std::ptrdiff_t>(from), up_cost_.end(), kInfCost);
  std::fill(up_step_.begin() + static_cast<std::ptrdiff_t>(from), up_step_.end(), Step{});
  for (const Seed& s : seeds_) {
    if (s.place >= from && s.cost_s < up_cost_[s.place]) {
      up_cost_[s.place] = s.cost_s;
      up_step_[s.place] = Step{kNoCchArc, s.start};
    }
  }
  // Every arc points up and the members ascend, so the vertices an arc comes from are final
  // before the sweep reaches its head.
  for (std::size_t j = from; j < up_set_.size(); ++j) {
    double best = up_cost_[j];
    Step step = up_step_[j];
    for (std::uint32_t k = up_first_[j]; k < up_first_[j + 1]; ++k) {
      const double c = add_cost(up_cost_[up_arcs_[k].tail_place], up_weight_s_[k]);
      if (c < best) {
        best = c;
        step = Step{up_arcs_[k].tail_place, up_arcs_[k].arc};
      }
    }
    up_cost_[j] = best;
    up_step_[j] = step;
  }
}

void CchSearchSpace::refresh_start() {
  if (seed()) sweep(0);
}

double CchSearchSpace::move_starts(std::vector<EdgePoint> starts) {
  flat_.set_starts(std::move(starts));
  std::vector<std::uint32_t> from;
  for (const EdgePoint& s : flat_.starts()) from.push_back(topology_->rank(s.vertex()));
  std::sort(from.begin(), from.end());
  // Further along the same edges (most position reports): the same ancestors, and with one start
  // point the same sweep.
  if (from != start_ranks_) {
    start_ranks_ = from;
    std::vector<std::uint32_t> members;
    topology_->ancestors(from, members);
    if (members != up_set_) build_up(std::move(members));
  }
  refresh_start();
  return 0.0;
}

std::uint32_t CchSearchSpace::climb(std::uint32_t place, std::vector<std::uint32_t>& out) const {
  assert(up_cost_[place] < kInfCost);  // only a place the sweep reached has a path up to it
  // The walk ends at a seed, whose step names its start point.
  for (Step s = up_step_[place];; s = up_step_[s.from]) {
    if (s.from == kNoCchArc) return s.arc;
    out.push_back(s.arc);
  }
}

template <class F>
void CchSearchSpace::scan_batch(std::span<const std::uint32_t> arcs, std::vector<Vertex>& out, F&& on_up_arc) const {
  // Arc `arc`, open upward, of the member at `place`: its entry among the member's open upward
  // arcs, which ascend by id, from `j` on.
  const auto slot_of = [&](std::uint32_t place, std::uint32_t arc, std::size_t& j) {
    const auto outs = metric_->upper_out(up_set_[place]);
    while (outs[j].arc < arc) ++j;
    assert(outs[j].arc == arc);
    return up_slot_[up_out_first_[place] + j];
  };
  if (!std::is_sorted(arcs.begin(), arcs.end())) {
    for (std::uint32_t arc : arcs) {
      const std::uint32_t x = topology_->tail(arc);
      if (metric_->open(arc, false) && in_down(x)) out.push_back(Vertex{topology_->head(arc)});
      if (!metric_->open(arc, true)) continue;
      const auto it = std::lower_bound(up_set_.begin(), up_set_.end(), x);
      if (it == up_set_.end() || *it != x) continue;
      const auto place = static_cast<std::uint32_t>(it - up_set_.begin());
      const auto outs = metric_->upper_out(x);
      std::size_t j = static_cast<std::size_t>(
          std::lower_bound(outs.begin(), outs.end(), arc, [](const CchDownArc& a, std::uint32_t id) { return a.arc < id; }) -
          outs.begin());
      on_up_arc(arc, place, slot_of(place, arc, j));
    }
    return;
  }
  // Arc ids are grouped by their lower end: member x's arcs are [first_up(x), first_up(x + 1)).
  // Each half's members are ascending, so one forward pass over the batch serves each half.
  const auto scan = [&](const std::vector<std::uint32_t>& members, auto&& f) {
    auto it = arcs.begin();
    for (std::uint32_t place = 0; place < members.size(); ++place) {
      const std::uint32_t x = members[place];
      it = std::lower_bound(it, arcs.end(), topology_->first_up(x));
      if (it == arcs.end()) return;
      std::size_t j = 0;  // the member's own cursor, for the upward half's slots
      for (const std::uint32_t hi = topology_->first_up(x + 1); it != arcs.end() && *it < hi; ++it) f(*it, place, j);
    }
  };
  scan(down_set_, [&](std::uint32_t arc, std::uint32_t, std::size_t&) {
    if (metric_->open(arc, false)) out.push_back(Vertex{topology_->head(arc)});
  });
  scan(up_set_, [&](std::uint32_t arc, std::uint32_t place, std::size_t& j) {
    if (metric_->open(arc, true)) on_up_arc(arc, place, slot_of(place, arc, j));
  });
}

void CchSearchSpace::vertices_on_arcs(std::span<const std::uint32_t> arcs, std::vector<Vertex>& out) const {
  out.clear();
  bool upward_half = false;
  scan_batch(arcs, out, [&](std::uint32_t, std::uint32_t, std::uint32_t) { upward_half = true; });
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  if (upward_half) out.push_back(start());
}

void CchSearchSpace::arcs_changed(std::span<const std::uint32_t> arcs, std::vector<Vertex>& out) {
  out.clear();
  std::size_t lowest = up_set_.size();  // the lowest place whose arcs in moved
  scan_batch(arcs, out, [&](std::uint32_t arc, std::uint32_t place, std::uint32_t slot) {
    double& w = up_weight_s_[slot];
    const double now = metric_->up_s(arc);
    if (w == now) return;
    w = now;
    // The head lies above the tail's place; where that is at or above `lowest` it cannot lower it.
    if (place + 1 >= lowest) return;
    const auto head = std::lower_bound(up_set_.begin() + place + 1, up_set_.end(), topology_->head(arc));
    lowest = std::min(lowest, static_cast<std::size_t>(head - up_set_.begin()));
  });
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  if (lowest < up_set_.size()) {
    sweep(lowest);
    out.push_back(start());
  }
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
  std::vector<std::uint32_t> vertices, arcs;
  const auto unpack = [&](std::uint32_t arc, bool upward) {
    vertices.clear();
    metric_->unpack(arc, upward, vertices);
    for (std::uint32_t v : vertices) edges.push_back(topology_->turns().edge_of(v));
  };
  for (const Via& via : vias) {
    if (via.kind == Via::Kind::start) {
      arcs.clear();
      edges.push_back(starts()[climb(via.arc, arcs)].edge);
      for (auto it = arcs.rbegin(); it != arcs.rend(); ++it) unpack(*it, true);
    } else if (via.kind == Via::Kind::down) {
      unpack(via.arc, false);
    } else {
      edges.push_back(via.edge);
    }
  }
  return flat_.route_along(std::move(edges));
}

std::size_t CchSearchSpace::heap_bytes() const {
  return flat_.heap_bytes() + (start_ranks_.capacity() + up_set_.capacity() + up_first_.capacity() + up_slot_.capacity() + up_out_first_.capacity() +
                              down_set_.capacity() + down_first_.capacity()) *
                             sizeof(std::uint32_t) +
         up_arcs_.capacity() * sizeof(UpArc) + down_arcs_.capacity() * sizeof(CchDownArc) + targets_.capacity() * sizeof(Target) +
         meetings_.capacity() * sizeof(Meeting) + seeds_.capacity() * sizeof(Seed) +
         (up_weight_s_.capacity() + up_cost_.capacity()) * sizeof(double) + up_step_.capacity() * sizeof(Step);
}

}  // namespace corridor::planner
