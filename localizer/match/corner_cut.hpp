// How the distance a vehicle drives through a vertex of its road differs from the road's centre
// lines: it rounds the corner on an arc instead of running to the vertex and turning there (which
// saves it distance whichever way it turns), and it keeps to its side of a two-way road, which
// saves it more through a turn to that side and gives some back through a turn away from it.
// Odometry and a receiver's speed measure what it drives; the map matcher and the smoother move
// along the centre lines. A turn sharper than 149° counts as 149°: a hairpin between two roads is
// still rounded (Monaco's are, and dropping their saving cost 0.04 points of edge share at σ 15 m), and
// a turn back onto the road it came by is for the caller to leave out (the odometry's matcher
// does).
#pragma once

#include <algorithm>
#include <cmath>

#include "maps/geo.hpp"
#include "maps/road_graph.hpp"

namespace corridor::localizer {

struct CornerModel {
  double radius_m = 8.0;       // the arc a vehicle rounds a corner on (less where the road's pieces are short)
  double lane_offset_m = 1.75;  // half a 3.5 m lane: how far to its side of a two-way road's centre line
};

inline constexpr double kMaxCornerRad = 2.6;  // 149°: a sharper hairpin saves what this one would

struct CornerCut {
  double saving_m = 0;      // centre lines minus the driven distance (negative: the vehicle drives further)
  double half_width_m = 0;  // along the centre lines either side of the vertex, where the difference builds up
};

// The vertex turns by turn_rad (positive towards the side traffic keeps to), between pieces
// before_m and after_m long; lane_offset_m is the vehicle's offset there (0 on a one-way road,
// whose centre line is its carriageway's middle).
inline CornerCut corner_cut(double turn_rad, double before_m, double after_m, double radius_m, double lane_offset_m) {
  if (!(std::abs(turn_rad) >= 1e-3)) return {};  // straight on, or NaN
  const double theta = std::clamp(turn_rad, -kMaxCornerRad, kMaxCornerRad);
  const double abs_theta = std::abs(theta);
  const double tan_half = std::tan(0.5 * abs_theta);
  const double r = std::max(0.0, std::min(radius_m, 0.5 * std::min(before_m, after_m) / tan_half));
  const double tangent = r * tan_half;
  CornerCut cut;
  cut.saving_m = 2.0 * tangent - r * abs_theta + lane_offset_m * theta;
  cut.half_width_m = std::max({tangent, std::abs(cut.saving_m), 0.5});  // the driven distance keeps growing
  return cut;
}

// The turn from direction a to direction b (local frame, x east, y north), in radians, positive
// towards the side the graph's traffic keeps to.
inline double turn_towards_traffic_side_rad(const maps::RoadGraph& g, double ax, double ay, double bx, double by) {
  const double right = -std::atan2(ax * by - ay * bx, ax * bx + ay * by);  // clockwise: a right turn
  return g.left_hand_traffic() ? -right : right;
}

}  // namespace corridor::localizer
