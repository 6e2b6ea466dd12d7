// Smooths a matched chain along its own path. Matching projects each fix onto the road, which
// removes the error across the road but keeps the error along it (σ of the GPS); a vehicle's
// distance along its path changes smoothly, and receivers measure speed well (Doppler). So the
// distance driven is estimated with a constant-velocity Kalman filter over the fixes' projections
// and speeds, and a Rauch–Tung–Striebel pass backwards (batch), then mapped back onto the path's
// edges. This is what brings the error along the road down, and with it the wrong-edge choices
// that a few metres of along-road error cause at junctions.
// Before that, a loop in the matched path that the fixes' speeds say was not driven (fixes
// scattered over a small roundabout) is taken out, and its fixes put on the road into or out of it;
// and the chain is smoothed in parts where the path between two points is far longer than the
// fixes moved, or than the speeds say was driven (a detour round a road the graph lacks).
// The filter runs on the distance the vehicle drove, which the speeds measure: a vehicle rounds
// corners and keeps to its side of the road, so it drives less than the centre lines through a
// turn, most through a right turn where traffic keeps right (corner_cut.hpp).
#pragma once

#include <span>
#include <vector>

#include "localizer/match/corner_cut.hpp"
#include "localizer/match/gps_fix.hpp"
#include "maps/road_graph.hpp"
#include "planner/bounded_search.hpp"

namespace corridor::localizer {

struct SmootherConfig {
  double acceleration_sigma = 1.5;   // m/s², the process noise of the constant-velocity model
  double speed_sigma_mps = 0.5;      // of a receiver's speed
  double sigma_base_m = 4.0;         // position σ = HDOP × this, as the matcher's emission
  double default_hdop = 1.5;
  double speed_gap_s = 30.0;         // the speeds say nothing of the distance driven over longer gaps
  // The distance driven is not the distance along the centre lines (corner_cut.hpp; radius 0 and
  // offset 0: the centre lines).
  CornerModel corner;
};

// `points` is one unbroken chain matched from `fixes` (same length, first and last matched).
// A point not matched in between (a fix the matcher set aside as an outlier) adds no measurement;
// the filter places it on the path by its time, and it comes back matched (except between the two
// parts of a chain split at a loop, where it stays unmatched). Returns the smoothed
// points; where the path between two points cannot be rebuilt, the chain is returned unchanged.
std::vector<MatchedPoint> smooth_along_path(const maps::RoadGraph& graph, planner::BoundedDistances& distances,
                                            std::span<const GpsFix> fixes, std::span<const MatchedPoint> points,
                                            const SmootherConfig& config = {});

}  // namespace corridor::localizer
