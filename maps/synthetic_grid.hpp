// Generates perturbed grid road networks: benchmark graphs of any size and random test graphs.
#pragma once

#include <cstdint>

#include "maps/road_graph.hpp"

namespace corridor::maps {

struct GridSpec {
  std::uint32_t rows = 10;
  std::uint32_t cols = 10;
  double spacing_m = 200.0;
  double jitter_fraction = 0.3;     // node displacement, as a fraction of spacing
  double removal_fraction = 0.05;   // streets removed at random
  double oneway_fraction = 0.2;     // remaining streets made one-way, random direction
  double diagonal_fraction = 0.05;  // extra diagonal streets
  double min_speed_kmh = 30.0;
  double max_speed_kmh = 90.0;
  double signal_fraction = 0.3;  // intersections with traffic signals
  std::uint64_t seed = 1;
  LatLon origin{47.14, 9.52};  // anywhere valid; only the local frame matters
};

// The largest strongly connected part of the generated grid.
RoadGraph make_perturbed_grid(const GridSpec& spec);

}  // namespace corridor::maps
