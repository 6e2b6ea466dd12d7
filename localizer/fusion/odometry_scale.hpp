// The odometry's scale, calibrated against the GPS receiver's speed while GPS is followed.
//
// A stereo odometry's distances carry a scale error that stays for hundreds of metres (the
// baseline's calibration, the scene's depth): 0.62 % on our VO's drives (docs/experiments/vo.md),
// 6 m along the road after a 1 km outage, which is the outage's main along-road error. A receiver's
// Doppler speed measures the distance driven without that error, and without the fixes' position
// noise: between two fixes it is the mean of their speeds times the interval (exact for a constant
// acceleration). Summed over many intervals against the odometry's own metres over the same
// intervals, the ratio is the scale; its noise falls with the square root of the intervals.
// This is what a car's dead reckoning does with its wheel odometer's scale factor.
//
// Only intervals where the vehicle drove (both speeds above min_speed_mps, so a receiver's speed
// at a stop, which is mostly noise, never counts), no longer than max_interval_s, and whose ratio
// is plausible (within max_pair_error of 1: a VO glitch or a speed spike) are summed. Older
// intervals fade with the odometry's metres (memory_m), so a scale that changes with the scene is
// followed. Until min_calibrated_m of odometry has been summed, or without speeds at all, the
// factor is 1: the odometry as it came.
#pragma once

#include <optional>

namespace corridor::localizer {

struct OdometryScaleConfig {
  bool enabled = true;
  double min_speed_mps = 3.0;       // both ends of an interval at least this fast
  double max_interval_s = 2.0;      // a longer interval (a missed fix) is skipped
  double max_pair_error = 0.25;     // an interval's ratio beyond 1 ± this is skipped
  double memory_m = 3000.0;         // older odometry metres fade with this e-folding length
  double min_calibrated_m = 300.0;  // the factor stays 1 until this much is summed
  double max_correction = 0.05;     // the factor stays within 1 ± this
};

class OdometryScale {
 public:
  explicit OdometryScale(OdometryScaleConfig config = {}) : config_(config) {}

  // A good fix at time_s with the receiver's speed (if it gave one), when the odometry had
  // reported odometry_m in all (its own, uncorrected, metres).
  void on_fix(double time_s, std::optional<double> speed_mps, double odometry_m);
  // What to multiply the odometry's distances by.
  [[nodiscard]] double factor() const { return factor_; }
  // The odometry metres summed, after fading (0 until an interval counted).
  [[nodiscard]] double calibrated_m() const { return odometry_sum_m_; }

 private:
  OdometryScaleConfig config_;
  struct Last {
    double time_s = 0;
    double speed_mps = 0;
    double odometry_m = 0;
  };
  std::optional<Last> last_;
  double doppler_sum_m_ = 0;
  double odometry_sum_m_ = 0;
  double factor_ = 1.0;
};

}  // namespace corridor::localizer
