// Random graphs and random edge points for planner tests.
#pragma once

#include <random>

#include "maps/synthetic_grid.hpp"
#include "planner/travel_cost.hpp"

namespace corridor::planner::testing {

inline maps::RoadGraph random_grid(std::uint64_t seed, std::uint32_t rows, std::uint32_t cols) {
  maps::GridSpec spec;
  spec.rows = rows;
  spec.cols = cols;
  spec.seed = seed;
  spec.removal_fraction = 0.1;
  spec.oneway_fraction = 0.3;
  spec.diagonal_fraction = 0.1;
  return maps::make_perturbed_grid(spec);
}

// A profile under which the edge-based graph behaves as the node-based one: turns cost nothing and
// a U-turn is allowed anywhere. For tests whose expected costs are worked out node by node.
inline VehicleProfile free_turns(double vmax_mps) {
  VehicleProfile p;
  p.vmax_mps = vmax_mps;
  p.turn_penalty_s = 0;
  p.crossing_penalty_s = 0;
  p.uturn_policy = UturnPolicy::anywhere;
  p.uturn_penalty_s = 0;
  return p;
}

// The graph with random turn restrictions added: via-node and via-way (two to three via edges), no_
// and only_, of every mode, some lifted for emergency vehicles. What binds is the profile's business.
inline maps::RoadGraph with_random_restrictions(const maps::RoadGraph& g, std::uint64_t seed, std::size_t count) {
  std::mt19937_64 rng(seed);
  maps::RoadGraphData d = g.data();
  d.restrictions = {};
  std::uniform_int_distribution<std::uint32_t> any_edge(0, static_cast<std::uint32_t>(g.edge_count() - 1));
  for (std::size_t k = 0; k < count; ++k) {
    std::vector<EdgeId> path{EdgeId{any_edge(rng)}};
    const int length = std::uniform_int_distribution<int>(2, 4)(rng) == 2 ? 2 : std::uniform_int_distribution<int>(3, 5)(rng);
    while (static_cast<int>(path.size()) < length) {
      std::vector<EdgeId> next;
      for (EdgeId f : g.out_edges(g.head(path.back()))) {
        if (f != g.twin(path.back()) || std::uniform_int_distribution<int>(0, 4)(rng) == 0) next.push_back(f);
      }
      if (next.empty()) break;
      path.push_back(next[std::uniform_int_distribution<std::size_t>(0, next.size() - 1)(rng)]);
    }
    if (path.size() < 2) continue;
    const auto mode = static_cast<maps::RestrictionMode>(std::uniform_int_distribution<int>(0, 5)(rng));
    // One in four names an `except`: any set of vehicle classes, so that overlapping restrictions
    // with different lists meet on one turn.
    const bool excepted = std::uniform_int_distribution<int>(0, 3)(rng) == 0;
    const auto except = static_cast<std::uint8_t>(excepted ? std::uniform_int_distribution<int>(1, 63)(rng) : 0);
    d.restrictions.add(path, std::uniform_int_distribution<int>(0, 3)(rng) == 0, mode, except);
  }
  return maps::RoadGraph(std::move(d));
}

// `g` with a 3 m height limit on about one edge in `every` (a fire engine, 3.5 m high, does not
// fit; an ambulance does).
inline maps::RoadGraph with_random_height_limits(const maps::RoadGraph& g, std::uint64_t seed, std::uint32_t every) {
  std::mt19937_64 rng(seed * 7919);
  maps::RoadGraphData d = g.data();
  d.edge_limits.clear();
  for (std::uint32_t e = 0; e < g.edge_count(); ++e) {
    if (std::uniform_int_distribution<std::uint32_t>(0, every - 1)(rng) == 0) d.edge_limits.push_back({EdgeId{e}, 3.0f, 0.0f, 0.0f});
  }
  return maps::RoadGraph(std::move(d));
}

// `g` with a gate or toll booth (maps::RoadGraph::stop_at) on about one node in `every`, which the
// profile's barrier_delay_s charges.
inline maps::RoadGraph with_random_stops(const maps::RoadGraph& g, std::uint64_t seed, std::uint32_t every) {
  std::mt19937_64 rng(seed * 104729);
  maps::RoadGraphData d = g.data();
  d.node_stop.assign(g.node_count(), 0);
  for (auto& s : d.node_stop) s = std::uniform_int_distribution<std::uint32_t>(0, every - 1)(rng) == 0 ? 1 : 0;
  return maps::RoadGraph(std::move(d));
}

// The profiles the randomized oracles cycle through: the ambulance, a fire engine, free turns, and
// U-turns anywhere at a price.
inline VehicleProfile oracle_profile(std::uint64_t seed, double vmax_mps) {
  VehicleProfile p = seed % 4 == 1 ? fire_engine_profile() : seed % 4 == 2 ? free_turns(vmax_mps) : ambulance_profile();
  if (seed % 4 == 3) {
    p.uturn_policy = UturnPolicy::anywhere;
    p.uturn_penalty_s = 12.0;
    p.except_classes = 0;
    p.barrier_delay_s = 45.0;
  }
  p.vmax_mps = vmax_mps;
  return p;
}

inline EdgePoint random_point(const maps::RoadGraph& g, std::mt19937_64& rng) {
  const EdgeId e{std::uniform_int_distribution<std::uint32_t>(0, static_cast<std::uint32_t>(g.edge_count() - 1))(rng)};
  // Offsets at the ends are the interesting corner cases; pick them often.
  const int kind = std::uniform_int_distribution<int>(0, 3)(rng);
  const double len = g.length_m(e);
  const double offset = kind == 0 ? 0.0 : kind == 1 ? len : std::uniform_real_distribution<double>(0.0, len)(rng);
  return {e, offset};
}

inline std::vector<EdgePoint> with_twin(const maps::RoadGraph& g, EdgePoint p) {
  std::vector<EdgePoint> out{p};
  if (g.twin(p.edge).valid()) out.push_back({g.twin(p.edge), g.length_m(p.edge) - p.offset_m});
  return out;
}

}  // namespace corridor::planner::testing
