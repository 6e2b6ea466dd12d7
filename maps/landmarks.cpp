#include "maps/landmarks.hpp"

#include <cmath>
#include <functional>
#include <limits>
#include <queue>
#include <utility>

#include "maps/road_graph.hpp"

namespace corridor::maps {
namespace {

using Ticks = std::uint64_t;
constexpr Ticks kInf = std::numeric_limits<Ticks>::max();

// One-to-all Dijkstra in ticks, forward (out-edges) or backward (in-edges).
class TickDijkstra {
 public:
  TickDijkstra(const RoadGraphData& d, std::span<const std::uint32_t> weight) : d_(d), weight_(weight) {}

  const std::vector<Ticks>& run(NodeId source, bool forward) {
    dist_.assign(d_.node_x_m.size(), kInf);
    using Item = std::pair<Ticks, std::uint32_t>;
    std::priority_queue<Item, std::vector<Item>, std::greater<>> open;
    dist_[source.index()] = 0;
    open.emplace(0, source.v);
    while (!open.empty()) {
      // Plain copies, not a structured binding: clang (the fuzz build) does not let a lambda
      // capture a binding.
      const Ticks du = open.top().first;
      const std::uint32_t u = open.top().second;
      open.pop();
      if (du != dist_[u]) continue;
      auto relax = [&](std::uint32_t e, NodeId v) {
        const Ticks nd = du + weight_[e];
        if (nd < dist_[v.index()]) {
          dist_[v.index()] = nd;
          open.emplace(nd, v.v);
        }
      };
      if (forward) {
        for (auto e = d_.first_out[u]; e < d_.first_out[u + 1]; ++e) relax(e, d_.edge_head[e]);
      } else {
        for (auto i = d_.first_in[u]; i < d_.first_in[u + 1]; ++i) {
          const EdgeId e = d_.in_edge[i];
          relax(e.v, d_.edge_tail[e.index()]);
        }
      }
    }
    return dist_;
  }

 private:
  const RoadGraphData& d_;
  std::span<const std::uint32_t> weight_;
  std::vector<Ticks> dist_;
};

std::uint32_t to_table(Ticks t) {
  // A reachable time at or above the sentinel (48 days of driving) cannot occur on a road map; it
  // is stored just below the sentinel rather than wrapping.
  return t == kInf ? kLandmarkUnreachable : static_cast<std::uint32_t>(std::min<Ticks>(t, kLandmarkUnreachable - 1));
}

}  // namespace

std::uint32_t free_flow_ticks(double length_m, double speed_mps) {
  const double ticks = std::floor(length_m / speed_mps / kLandmarkTickS);
  if (!(ticks >= 0.0)) return 0;
  return ticks >= static_cast<double>(kLandmarkUnreachable) ? kLandmarkUnreachable - 1 : static_cast<std::uint32_t>(ticks);
}

LandmarkTables compute_landmarks(const RoadGraphData& d, std::size_t count, std::span<const std::uint8_t> candidate) {
  const std::size_t n = d.node_x_m.size();
  const auto eligible = [&](std::size_t v) { return candidate.empty() || candidate[v] != 0; };
  std::size_t eligible_nodes = 0;
  for (std::size_t v = 0; v < n; ++v) eligible_nodes += eligible(v) ? 1 : 0;
  const std::size_t k = std::min(count, eligible_nodes);
  LandmarkTables t;
  if (k == 0) return t;
  std::vector<std::uint32_t> weight(d.edge_head.size());
  for (std::size_t e = 0; e < weight.size(); ++e) weight[e] = free_flow_ticks(d.edge_length_m[e], d.edge_speed_mps[e]);
  TickDijkstra dijkstra(d, weight);

  // nearest[v]: round trip from v to the closest landmark chosen so far (kInf when none reaches).
  std::vector<Ticks> nearest(n, kInf);
  auto add_round_trips = [&](const std::vector<Ticks>& there, const std::vector<Ticks>& back) {
    for (std::size_t v = 0; v < n; ++v) {
      const Ticks trip = there[v] == kInf || back[v] == kInf ? kInf : there[v] + back[v];
      nearest[v] = std::min(nearest[v], trip);
    }
  };
  std::size_t first_eligible = 0;
  while (!eligible(first_eligible)) ++first_eligible;
  auto farthest = [&] {
    // Among the candidates, unreachable nodes (kInf) win, so another component gets a landmark of
    // its own.
    std::size_t best = first_eligible;
    for (std::size_t v = first_eligible + 1; v < n; ++v) {
      if (eligible(v) && nearest[v] > nearest[best]) best = v;
    }
    return NodeId{static_cast<std::uint32_t>(best)};
  };

  // Seed from the first candidate: the first landmark is the node farthest from it, not the seed.
  {
    const std::vector<Ticks> there = dijkstra.run(NodeId{static_cast<std::uint32_t>(first_eligible)}, true);
    const std::vector<Ticks> back = dijkstra.run(NodeId{static_cast<std::uint32_t>(first_eligible)}, false);
    add_round_trips(there, back);
  }
  t.nodes.reserve(k);
  t.from_ticks.assign(n * k, kLandmarkUnreachable);
  t.to_ticks.assign(n * k, kLandmarkUnreachable);
  std::vector<Ticks> there;
  for (std::size_t i = 0; i < k; ++i) {
    const NodeId l = farthest();
    t.nodes.push_back(l);
    // The seed's round trips only chose the first landmark; distances to landmarks decide the rest.
    if (i == 0) nearest.assign(n, kInf);
    there = dijkstra.run(l, true);
    const std::vector<Ticks>& back = dijkstra.run(l, false);
    for (std::size_t v = 0; v < n; ++v) {
      t.from_ticks[v * k + i] = to_table(there[v]);
      t.to_ticks[v * k + i] = to_table(back[v]);
    }
    add_round_trips(there, back);
    nearest[l.index()] = 0;  // never chosen twice, even where the round trip is not unique
  }
  return t;
}

}  // namespace corridor::maps
