#include "localizer/fusion/simulated_odometry.hpp"

#include "localizer/match/bearing.hpp"

#include <cmath>

namespace corridor::localizer {

SimulatedOdometry::SimulatedOdometry(VoDriftModel model, std::uint64_t seed) : model_(model), rng_(seed) {
  scale_ = 1.0 + model_.scale_sigma * gauss_(rng_);
}

OdometryStep SimulatedOdometry::step(double time_s, maps::Point2 from, double from_heading_deg, maps::Point2 to,
                                     double to_heading_deg, std::optional<double> path_m) {
  const double d = path_m && std::isfinite(*path_m) && *path_m >= 0.0 ? *path_m : maps::distance_m(from, to);
  const double turn = wrap180(to_heading_deg - from_heading_deg) + model_.heading_deg_per_100m * d / 100.0 * gauss_(rng_);
  return {time_s, d * scale_, turn};
}

}  // namespace corridor::localizer
