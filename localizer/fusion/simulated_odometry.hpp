// Odometry simulated from a true trajectory with the errors our stereo VO showed on its drives
// (docs/experiments/vo.md): a per-drive scale error and a heading random walk. The localization
// study, `corridor localize` without a sequence, and the SUMO loop's onboard localizer use it.
#pragma once

#include <cstdint>
#include <optional>
#include <random>

#include "localizer/fusion/odometry_map_matcher.hpp"

namespace corridor::localizer {

struct VoDriftModel {
  double scale_sigma = 0.0062;           // translation error: t_err 0.62 %
  double heading_deg_per_100m = 0.24;    // rotation error: r_err 0.24°/100 m
};

class SimulatedOdometry {
 public:
  SimulatedOdometry(VoDriftModel model, std::uint64_t seed);

  // The increment from one true pose to the next (headings clockwise from north). The distance
  // driven is path_m when the caller knows it (a trajectory sampled at 1 Hz cuts each bend with a
  // chord, 1–2 % shorter than the road on a 30 m radius, where a 10 Hz odometry follows the
  // road), else the straight line between the poses.
  OdometryStep step(double time_s, maps::Point2 from, double from_heading_deg, maps::Point2 to, double to_heading_deg,
                    std::optional<double> path_m = std::nullopt);
  // The drive's scale: reported distance over true distance.
  [[nodiscard]] double scale() const { return scale_; }

 private:
  VoDriftModel model_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> gauss_{0.0, 1.0};
  double scale_ = 1.0;  // drawn once per drive
};

}  // namespace corridor::localizer
