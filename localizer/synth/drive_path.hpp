// A vehicle's drive along a road polyline, as the camera would move: corners rounded to drivable
// curves, speed limited by lateral acceleration, sampled once per camera frame.
#pragma once

#include <vector>

#include "maps/geo.hpp"

namespace corridor::localizer::synth {

struct DriveOptions {
  double frame_rate_hz = 10.0;
  double cruise_speed_mps = 10.0;
  double max_lateral_accel_mps2 = 2.0;
  double max_long_accel_mps2 = 1.5;
  double corner_smoothing_m = 4.0;  // Gaussian sigma applied to the polyline before driving it
  double max_length_m = 0.0;        // 0: drive the whole polyline
};

struct DriveSample {
  double time_s = 0.0;
  maps::Point2 position;   // map frame, metres east/north
  double heading_rad = 0;  // direction of travel, counter-clockwise from east
  double arc_m = 0.0;      // distance driven so far
};

// The smoothed centre line that the drive follows, sampled every `spacing_m`.
std::vector<maps::Point2> smooth_polyline(const std::vector<maps::Point2>& polyline, double sigma_m,
                                          double spacing_m = 0.5);

// Total heading change, in degrees, along the first `length_m` of the polyline once its corners are
// rounded as a drive rounds them: how much a drive of that length turns.
double total_turn_deg(const std::vector<maps::Point2>& polyline, double corner_smoothing_m, double length_m);

// Throws std::invalid_argument when the polyline is shorter than 20 m.
std::vector<DriveSample> plan_drive(const std::vector<maps::Point2>& polyline, const DriveOptions& options);

}  // namespace corridor::localizer::synth
