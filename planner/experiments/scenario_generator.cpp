#include "planner/experiments/scenario_generator.hpp"

#include <algorithm>
#include <stdexcept>

#include "planner/one_to_one_search.hpp"

namespace corridor::planner {

std::uint64_t Rng::next() {
  std::uint64_t z = (state_ += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

double Rng::uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }

double Rng::uniform(double lo, double hi) { return lo == hi ? lo : lo + (hi - lo) * uniform(); }

std::uint32_t Rng::below(std::uint32_t n) {
  if (n == 0) throw std::invalid_argument("Rng::below(0)");
  return static_cast<std::uint32_t>((next() >> 32) * n >> 32);
}

std::uint64_t derive_seed(std::uint64_t seed, std::string_view stream) {
  std::uint64_t h = 0xcbf29ce484222325ULL;  // FNV-1a
  for (char c : stream) h = (h ^ static_cast<unsigned char>(c)) * 0x100000001b3ULL;
  Rng mix(seed ^ h);
  return mix.next();
}

std::vector<double> draw_signal_delays(std::span<const std::uint8_t> has_signal, DelayRange range, Rng& rng) {
  std::vector<double> delays(has_signal.size(), 0.0);
  for (std::size_t v = 0; v < has_signal.size(); ++v) {
    if (has_signal[v] != 0) delays[v] = rng.uniform(range.lo_s, range.hi_s);
  }
  return delays;
}

std::vector<double> draw_signal_delays(const maps::RoadGraph& graph, DelayRange range, Rng& rng) {
  return draw_signal_delays(graph.data().node_signalized, range, rng);
}

std::vector<std::uint8_t> junction_mask(const maps::RoadGraph& graph) {
  std::vector<std::uint8_t> mask(graph.node_count(), 0);
  std::vector<NodeId> neighbours;
  for (NodeId v : graph.nodes()) {
    neighbours.clear();
    for (EdgeId e : graph.out_edges(v)) neighbours.push_back(graph.head(e));
    for (EdgeId e : graph.in_edges(v)) neighbours.push_back(graph.tail(e));
    std::sort(neighbours.begin(), neighbours.end());
    const auto distinct = std::unique(neighbours.begin(), neighbours.end()) - neighbours.begin();
    mask[v.index()] = distinct >= 3 ? 1 : 0;
  }
  return mask;
}

CongestionSites pick_congestion_sites(const maps::RoadGraph& graph, const Route& plan, CongestionPlacement placement,
                                      Rng& rng) {
  CongestionSites sites;
  auto on_route = [&](EdgeId e) { return std::find(plan.edges.begin(), plan.edges.end(), e) != plan.edges.end(); };
  // Candidates with the time the planned vehicle reaches their tail; tail i of edge i is the
  // head of edge i-1, reached at arrival_s[i-1].
  std::vector<std::pair<EdgeId, double>> along;
  std::vector<std::pair<EdgeId, double>> near;
  for (std::size_t i = 1; i < plan.edges.size(); ++i) along.emplace_back(plan.edges[i], plan.arrival_s[i - 1]);
  // Off the route but within two intersections of it: the detours a dynamic vehicle may take. They
  // may jam at any time during the trip, also after a detouring vehicle has committed to them.
  const double trip_s = plan.arrival_s.empty() ? 0.0 : plan.arrival_s.back();
  auto is_candidate = [&](EdgeId e) {
    const bool u_turn = std::any_of(plan.edges.begin(), plan.edges.end(), [&](EdgeId r) { return graph.twin(r) == e; });
    const bool seen = std::any_of(near.begin(), near.end(), [&](const auto& c) { return c.first == e; });
    return !on_route(e) && !u_turn && !seen;
  };
  std::vector<NodeId> route_nodes{graph.tail(plan.edges.front())};
  route_nodes.insert(route_nodes.end(), plan.nodes.begin(), plan.nodes.end() - 1);
  for (NodeId v : route_nodes) {
    for (EdgeId e : graph.out_edges(v)) {
      if (!is_candidate(e)) continue;
      near.emplace_back(e, trip_s);
      for (EdgeId f : graph.out_edges(graph.head(e))) {
        if (is_candidate(f)) near.emplace_back(f, trip_s);
      }
    }
  }

  auto take = [&](std::vector<std::pair<EdgeId, double>>& pool, std::uint32_t count) {
    for (std::uint32_t k = 0; k < count && !pool.empty(); ++k) {
      const std::uint32_t i = rng.below(static_cast<std::uint32_t>(pool.size()));
      sites.edges.push_back(pool[i].first);
      sites.reach_s.push_back(pool[i].second);
      pool.erase(pool.begin() + i);
    }
  };
  take(along, placement.on_route);
  take(near, placement.near_route);
  return sites;
}

std::vector<CongestionEvent> draw_events(const CongestionSites& sites, DelayRange queue, Rng& rng) {
  std::vector<CongestionEvent> events;
  for (std::size_t i = 0; i < sites.edges.size(); ++i) {
    // (0, reach]: 1 - uniform() is in (0, 1].
    const double time = sites.reach_s[i] * (1.0 - rng.uniform());
    events.push_back({time, sites.edges[i], rng.uniform(queue.lo_s, queue.hi_s)});
  }
  return events;
}

std::pair<NodeId, NodeId> draw_pair(const maps::RoadGraph& graph, double min_distance_m, std::uint32_t min_edges,
                                    VehicleProfile vehicle, Rng& rng) {
  const auto n = static_cast<std::uint32_t>(graph.node_count());
  const CostOverlay overlay(graph);
  const TravelCost cost(graph, overlay, vehicle);
  OneToOneSearch search;
  for (int attempt = 0; attempt < 10000; ++attempt) {
    const NodeId s{rng.below(n)};
    const NodeId t{rng.below(n)};
    if (s == t || maps::distance_m(graph.position(s), graph.position(t)) < min_distance_m) continue;
    if (graph.out_edges(s).empty() || graph.in_edges(t).empty()) continue;
    const Route r = search.run(SearchSpace(cost, node_departures(graph, s), node_arrivals(graph, t)), true);
    if (r.found && r.edges.size() >= min_edges) return {s, t};
  }
  throw std::runtime_error("no start/goal pair found that is far enough apart on this graph");
}

}  // namespace corridor::planner
