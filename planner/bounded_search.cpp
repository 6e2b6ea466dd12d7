#include "planner/bounded_search.hpp"

#include <algorithm>
#include <functional>
#include <stdexcept>

namespace corridor::planner {

BoundedDistances::BoundedDistances(std::size_t node_count)
    : dist_(node_count, kInfCost), stamp_(node_count, 0), settled_(node_count, 0), parent_edge_(node_count) {}

std::vector<EdgeId> BoundedDistances::path_to(const maps::RoadGraph& graph, NodeId v) const {
  std::vector<EdgeId> path;
  if (settled_[v.index()] != round_) return path;
  for (NodeId at = v; parent_edge_[at.index()].valid();) {
    const EdgeId e = parent_edge_[at.index()];
    path.push_back(e);
    at = graph.tail(e);
    if (path.size() > dist_.size()) break;  // cannot happen on a consistent run; never loop
  }
  std::reverse(path.begin(), path.end());
  return path;
}

std::size_t BoundedDistances::run(const maps::RoadGraph& graph_, NodeId source, double max_length_m,
                                  std::span<const NodeId> targets) {
  if (graph_.node_count() != dist_.size()) throw std::invalid_argument("search arrays sized for another graph");
  if (++round_ == 0) {  // stamp wrap-around: start afresh
    std::fill(stamp_.begin(), stamp_.end(), 0);
    std::fill(settled_.begin(), settled_.end(), 0);
    round_ = 1;
  }
  std::size_t targets_left = 0;
  for (NodeId t : targets) targets_left += t.valid() ? 1 : 0;
  heap_.clear();
  dist_[source.index()] = 0.0;
  stamp_[source.index()] = round_;
  parent_edge_[source.index()] = EdgeId{};
  heap_.emplace_back(0.0, source.v);
  std::size_t settled = 0;
  const auto later = std::greater<>{};
  while (!heap_.empty()) {
    std::pop_heap(heap_.begin(), heap_.end(), later);
    const auto [d, u] = heap_.back();
    heap_.pop_back();
    if (settled_[u] == round_ || d > dist_[u]) continue;
    settled_[u] = round_;
    ++settled;
    if (targets_left > 0 && std::find(targets.begin(), targets.end(), NodeId{u}) != targets.end()) {
      // A target listed twice is still settled once.
      targets_left -= static_cast<std::size_t>(std::count(targets.begin(), targets.end(), NodeId{u}));
      if (targets_left == 0) break;
    }
    for (EdgeId e : graph_.out_edges(NodeId{u})) {
      const double nd = d + graph_.length_m(e);
      if (nd > max_length_m) continue;
      const std::uint32_t v = graph_.head(e).v;
      if (stamp_[v] != round_ || nd < dist_[v]) {
        stamp_[v] = round_;
        dist_[v] = nd;
        parent_edge_[v] = e;
        heap_.emplace_back(nd, v);
        std::push_heap(heap_.begin(), heap_.end(), later);
      }
    }
  }
  return settled;
}

}  // namespace corridor::planner
