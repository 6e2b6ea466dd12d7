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
