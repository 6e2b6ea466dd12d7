// Compass angles of the road graph, shared by the matchers: a road's bearing at a point (clockwise
// from north, degrees) and the differences between headings.
#pragma once

#include <algorithm>
#include <cmath>
#include <numbers>

#include "maps/road_graph.hpp"

namespace corridor::localizer {

// An angle difference folded into (-180, 180].
inline double wrap180(double d) {
  d = std::fmod(d, 360.0);
  if (d <= -180.0) d += 360.0;
  if (d > 180.0) d -= 360.0;
  return d;
}

// The unsigned angle between two headings, 0..180.
inline double angle_between_deg(double a, double b) { return std::abs(wrap180(a - b)); }

// The bearing of edge e around offset_m, over ±half_window_m of its geometry, in [0, 360).
inline double road_bearing_deg(const maps::RoadGraph& g, EdgeId e, double offset_m, double half_window_m = 2.0) {
  const double len = g.length_m(e);
  const maps::Point2 a = g.point_along(e, std::clamp(offset_m - half_window_m, 0.0, len));
  const maps::Point2 b = g.point_along(e, std::clamp(offset_m + half_window_m, 0.0, len));
  const double h = std::atan2(b.x_m - a.x_m, b.y_m - a.y_m) * 180.0 / std::numbers::pi;
  return h < 0.0 ? h + 360.0 : h;
}

}  // namespace corridor::localizer
