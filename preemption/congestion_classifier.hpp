// Decides whether an approach is congested, from whatever measurement is available, in a fixed
// order: the queue estimate, else detector occupancy, else the ratio of measured to free speed.
#pragma once

#include <optional>

#include "preemption/phase_selection.hpp"

namespace corridor::preemption {

struct CongestionClassifierConfig {
  double queue_high_veh = 6.0;     // a queue of at least this many vehicles is high congestion
  double occupancy_high = 0.30;    // detector occupancy (0..1) at or above this is high
  double speed_ratio_high = 0.50;  // measured / free-flow speed at or below this is high
};

struct ApproachMeasurement {
  std::optional<double> queue_veh;
  std::optional<double> occupancy;
  std::optional<double> speed_ratio;
  std::optional<double> queue_m;  // standing queue, metres back from the stop line (vicinity rules only)
};

// Without any measurement the approach is taken as low congestion.
CongestionLevel classify_congestion(const ApproachMeasurement& m, const CongestionClassifierConfig& c);

}  // namespace corridor::preemption
