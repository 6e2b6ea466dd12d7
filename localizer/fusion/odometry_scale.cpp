#include "localizer/fusion/odometry_scale.hpp"

#include <algorithm>
#include <cmath>

namespace corridor::localizer {

void OdometryScale::on_fix(double time_s, std::optional<double> speed_mps, double odometry_m) {
  if (!config_.enabled) return;
  if (!std::isfinite(time_s) || !std::isfinite(odometry_m) || !speed_mps || !std::isfinite(*speed_mps)) {
    last_.reset();  // an interval needs a speed at both ends
    return;
  }
  const Last now{time_s, *speed_mps, odometry_m};
  // A repeated time is no interval; an older one (a clock that went back, a replay started over)
  // starts the next interval afresh rather than stopping the calibration until time catches up.
  if (last_ && time_s == last_->time_s) return;
  if (!last_ || time_s < last_->time_s || odometry_m < last_->odometry_m) {
    last_ = now;
    return;
  }
  const Last before = *last_;
  last_ = now;
  const double dt = time_s - before.time_s;
  if (dt > config_.max_interval_s) return;
  if (before.speed_mps < config_.min_speed_mps || now.speed_mps < config_.min_speed_mps) return;
  const double doppler_m = 0.5 * (before.speed_mps + now.speed_mps) * dt;
  const double odometry_step_m = odometry_m - before.odometry_m;
  if (!(odometry_step_m > 0.0)) return;
  if (std::abs(doppler_m / odometry_step_m - 1.0) > config_.max_pair_error) return;
  // Fade what was summed by the metres just driven, then add this interval.
  const double keep = std::exp(-odometry_step_m / config_.memory_m);
  doppler_sum_m_ = keep * doppler_sum_m_ + doppler_m;
  odometry_sum_m_ = keep * odometry_sum_m_ + odometry_step_m;
  if (odometry_sum_m_ >= config_.min_calibrated_m) {
    factor_ = std::clamp(doppler_sum_m_ / odometry_sum_m_, 1.0 - config_.max_correction, 1.0 + config_.max_correction);
  }
}

}  // namespace corridor::localizer
