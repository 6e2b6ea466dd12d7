// A CchSearchSpace's construction: the goal side's targets and down set, the start side's up set
// with its ranges and parents, and where the two meet; also what a moved start rebuilds of them.
#include <algorithm>
#include <cassert>

#include "planner/cch_search_space.hpp"
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
  build_up(std::move(members), 0);
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
  down_range_.resize(down_set_.size());
  for (std::size_t i = 0; i < down_set_.size(); ++i) down_range_[i] = {topology_->first_up(down_set_[i]), topology_->first_up(down_set_[i] + 1)};
}

void CchSearchSpace::build_up(std::vector<std::uint32_t> members, std::size_t shared) {
  // Arcs are filed under their higher end, as the sweep reads them; each list ascends by lower
  // end, and so by arc id (ids ascend by lower end). The places below the shared top: [0, old_low)
  // now, [0, low) in the new half. A shared member at new place h was at h - low + old_low.
  const std::size_t n = members.size();
  const auto low = static_cast<std::uint32_t>(n - shared);
  const auto old_low = static_cast<std::uint32_t>(up_set_.size() - shared);
  const auto old_place = [&](std::size_t h) { return h - low + old_low; };
  // Where a shared head's kept arcs begin in its old list: the arcs from shared tails, which end
  // the list (it ascends by tail).
  const auto kept_from = [&](std::size_t h) {
    const auto b = up_arcs_.begin() + up_first_[old_place(h)], e = up_arcs_.begin() + up_first_[old_place(h) + 1];
    return static_cast<std::uint32_t>(std::partition_point(b, e, [&](const UpArc& a) { return a.tail_place < old_low; }) - up_arcs_.begin());
  };
  UpArrays& nx = spare_;
  nx.first.assign(n + 1, 0);
  heads_.clear();
  // The new members' arcs, from the metric; each ends at a member above its tail, new or shared.
  for (std::size_t i = 0; i < low; ++i) {
    auto at = members.begin() + static_cast<std::ptrdiff_t>(i);
    for (const CchDownArc& a : metric_->upper_out(members[i])) {
      at = gallop_to(at, members.end(), a.tail, [](std::uint32_t r) { return r; });
      heads_.push_back(static_cast<std::uint32_t>(at - members.begin()));
      ++nx.first[heads_.back() + 1];
    }
  }
  for (std::size_t h = low; h < n; ++h) nx.first[h + 1] += up_first_[old_place(h) + 1] - kept_from(h);
  for (std::size_t i = 1; i <= n; ++i) nx.first[i] += nx.first[i - 1];
  nx.arcs.resize(nx.first.back());
  nx.weight_s.resize(nx.first.back());
  nx.fill.assign(nx.first.begin(), nx.first.end() - 1);
  nx.slot.resize(heads_.size() + (shared == 0 ? 0 : up_slot_.size() - up_out_first_[old_low]));
  nx.out_first.resize(n + 1);
  std::uint32_t next = 0;
  for (std::uint32_t i = 0; i < low; ++i) {
    nx.out_first[i] = next;
    for (const CchDownArc& a : metric_->upper_out(members[i])) {
      const std::uint32_t k = nx.fill[heads_[next]]++;
      nx.slot[next++] = k;
      nx.arcs[k] = {i, a.arc};
      nx.weight_s[k] = metric_->up_s(a.arc);
    }
  }
  // The shared arcs follow the new ones into each shared head, with their weights as last
  // reported (arcs_changed keeps them so), tails moved to their new places.
  moved_slot_.resize(up_arcs_.size());
  for (std::size_t h = low; h < n; ++h) {
    for (std::uint32_t k = kept_from(h), e = up_first_[old_place(h) + 1]; k < e; ++k) {
      const std::uint32_t to = nx.fill[h]++;
      nx.arcs[to] = {up_arcs_[k].tail_place - old_low + low, up_arcs_[k].arc};
      nx.weight_s[to] = up_weight_s_[k];
      moved_slot_[k] = to;
    }
  }
  nx.range.resize(n);
  nx.parent.resize(n);
  for (std::size_t t = low; t < n; ++t) {
    const std::size_t o = old_place(t);
    nx.out_first[t] = next;
    for (std::uint32_t j = up_out_first_[o]; j < up_out_first_[o + 1]; ++j) nx.slot[next++] = moved_slot_[up_slot_[j]];
    nx.range[t] = up_range_[o];
    nx.parent[t] = up_parent_[o] == kNoCchArc ? kNoCchArc : up_parent_[o] - old_low + low;
  }
  nx.out_first[n] = next;
  up_set_ = std::move(members);
  up_first_.swap(nx.first);
  up_arcs_.swap(nx.arcs);
  up_weight_s_.swap(nx.weight_s);
  up_slot_.swap(nx.slot);
  up_out_first_.swap(nx.out_first);
  up_range_.swap(nx.range);
  up_parent_.swap(nx.parent);
  describe_up_members(0, low);
  find_meetings();
}

void CchSearchSpace::describe_up_members(std::size_t from, std::size_t to) {
  for (std::size_t i = from; i < to; ++i) {
    const std::uint32_t x = up_set_[i];
    up_range_[i] = {topology_->first_up(x), topology_->first_up(x + 1)};
    const std::uint32_t p = topology_->parent(x);
    up_parent_[i] = p == kNoCchArc ? kNoCchArc
                                   : static_cast<std::uint32_t>(std::lower_bound(up_set_.begin() + static_cast<std::ptrdiff_t>(i) + 1, up_set_.end(), p) -
                                                                up_set_.begin());
  }
}

void CchSearchSpace::find_meetings() {
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

}  // namespace corridor::planner
