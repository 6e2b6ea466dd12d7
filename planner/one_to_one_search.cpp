#include "planner/one_to_one_search.hpp"

#include <algorithm>
#include <queue>

namespace corridor::planner {

const char* to_string(Algorithm a) {
  switch (a) {
    case Algorithm::dijkstra: return "dijkstra";
    case Algorithm::astar: return "astar";
    case Algorithm::dstar_lite: return "dstar";
  }
  return "?";
}

void OneToOneSearch::prepare(std::size_t n) {
  if (dist_.size() != n) {
    dist_.assign(n, kInfCost);
    parent_.assign(n, 0);
    parent_edge_.assign(n, kInvalidEdge);
    stamp_.assign(n, 0);
    settled_.assign(n, 0);
    round_ = 0;
  }
  if (++round_ == 0) {  // stamp wrap-around: start afresh
    std::fill(stamp_.begin(), stamp_.end(), 0);
    round_ = 1;
  }
}

Route OneToOneSearch::run(const SearchSpace& space, bool use_heuristic, SearchStats* stats) {
  prepare(space.vertex_count());
  const Vertex s = space.start();
  const Vertex t = space.goal();
  auto dist = [&](Vertex v) { return stamp_[v.index()] == round_ ? dist_[v.index()] : kInfCost; };
  auto h = [&](Vertex v) { return use_heuristic ? space.h_to_goal_s(v) : 0.0; };

  using Item = std::pair<double, std::uint32_t>;  // (f, vertex), lazy deletion
  std::priority_queue<Item, std::vector<Item>, std::greater<>> open;
  stamp_[s.index()] = round_;
  dist_[s.index()] = 0.0;
  settled_[s.index()] = 0;
  open.emplace(h(s), s.v);
  SearchStats local;
  bool reached = false;
  while (!open.empty()) {
    const auto [f, uv] = open.top();
    open.pop();
    const Vertex u{uv};
    if (settled_[u.index()] != 0 && stamp_[u.index()] == round_) continue;
    settled_[u.index()] = 1;
    ++local.settled;
    if (u == t) {
      reached = true;
      break;
    }
    const double du = dist_[u.index()];
    space.for_each_successor(u, [&](Vertex v, double c, EdgeId via) {
      const double nd = add_cost(du, c);
      if (nd >= kInfCost) return;
      if (stamp_[v.index()] != round_) {
        stamp_[v.index()] = round_;
        settled_[v.index()] = 0;
      } else if (settled_[v.index()] != 0 || nd >= dist_[v.index()]) {
        return;
      }
      dist_[v.index()] = nd;
      parent_[v.index()] = u.v;
      parent_edge_[v.index()] = via;
      open.emplace(nd + h(v), v.v);
      ++local.pushes;
    });
  }
  if (stats != nullptr) *stats = local;

  if (!reached || dist(t) >= kInfCost) return space.route_along({});
  // Walk back G -> S. The first arc's via is the start edge, the last arc's via is the goal edge.
  std::vector<EdgeId> edges;
  for (Vertex v = t; v != s; v = Vertex{parent_[v.index()]}) edges.push_back(parent_edge_[v.index()]);
  std::reverse(edges.begin(), edges.end());
  return space.route_along(std::move(edges));
}

}  // namespace corridor::planner
