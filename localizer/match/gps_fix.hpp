// A position fix as a receiver reports it, and a fix matched onto the road graph: the plain structs
// the map matchers take and give.
#pragma once

#include <cmath>
#include <optional>

#include "maps/geo.hpp"
#include "maps/ids.hpp"

namespace corridor::localizer {

struct GpsFix {
  double time_s = 0;  // seconds, any epoch, increasing along a trace
  maps::LatLon position;
  std::optional<double> hdop;         // horizontal dilution of precision (1 = ideal)
  std::optional<double> heading_deg;  // course over ground, clockwise from north
  std::optional<double> speed_mps;
};

// The HDOP a matcher works with: the fix's, unless it is missing, zero, negative or not a number
// (a receiver's placeholder), when `default_hdop` stands in. Every σ taken from a fix uses this.
inline double usable_hdop(const GpsFix& fix, double default_hdop) {
  return fix.hdop && std::isfinite(*fix.hdop) && *fix.hdop > 0.0 ? *fix.hdop : default_hdop;
}

struct MatchedPoint {
  bool matched = false;  // false: no road near, or the chain broke here and nothing fits yet
  EdgeId edge;
  double offset_m = 0;       // along `edge`, in the edge's length units
  maps::Point2 point;        // on the road, local frame
  double distance_m = 0;     // from the raw fix to `point`
  double confidence = 0;     // the chosen candidate's share of the step's probability, 0..1
  bool chain_start = false;  // the first point after a break (gap, no candidate, impossible move, a restart)
  // Batch only: the fix, between two matched ones of its chain, was set aside as an outlier
  // (multipath). If `matched`, `point` is where the smoothed chain puts the vehicle at the fix's
  // time; without smoothing it stays unmatched. Fixes set aside at a chain's end, before a break,
  // stay unmatched and unflagged.
  bool outlier = false;
};

}  // namespace corridor::localizer
