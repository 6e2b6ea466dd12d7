// Noisy GPS traces with known truth, for tests and benchmarks of the matchers: a vehicle drives a
// random walk of the road graph (never straight back), one fix per period, with Gaussian noise and,
// now and then, a multipath outlier.
#pragma once

#include <cstdint>
#include <vector>

#include "localizer/match/gps_fix.hpp"
#include "maps/road_graph.hpp"

namespace corridor::localizer {

struct SyntheticTraceSpec {
  std::size_t edges = 40;          // edges driven
  double speed_mps = 12.0;
  double period_s = 1.0;
  double noise_sigma_m = 5.0;
  double outlier_share = 0.0;      // fixes displaced by outlier_m in a random direction
  double outlier_m = 60.0;
  std::uint64_t seed = 1;
};

struct SyntheticTrace {
  std::vector<GpsFix> fixes;
  std::vector<EdgeId> truth;        // the edge driven at each fix
  std::vector<maps::Point2> truth_point;  // where the vehicle really was
};

SyntheticTrace make_synthetic_trace(const maps::RoadGraph& graph, const SyntheticTraceSpec& spec);

}  // namespace corridor::localizer
