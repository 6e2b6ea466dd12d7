// Odometry accuracy against ground truth: the KITTI odometry metrics (mean translational error in %
// and rotational error in deg/100 m over all segments of 100…800 m, starting every 10 frames), the
// absolute trajectory RMSE after a rigid (SE(3), Umeyama) alignment, and end-point drift.
#pragma once

#include <optional>
#include <vector>

#include "localizer/vo/kitti_format.hpp"

namespace corridor::localizer {

struct TrajectoryMetrics {
  std::optional<double> t_err_pct;           // none when the drive is shorter than the shortest segment
  std::optional<double> r_err_deg_per_100m;
  std::vector<double> segment_lengths_m;     // the lengths actually evaluated
  int segments = 0;
  double ate_rmse_m = 0.0;
  double drift_pct = 0.0;                    // |end error| / distance driven
  double length_m = 0.0;                     // ground-truth distance driven
};

// `segment_lengths_m` empty: KITTI's 100…800 m. Both trajectories must have the same length.
TrajectoryMetrics evaluate_trajectory(const std::vector<Pose>& estimate, const std::vector<Pose>& ground_truth,
                                      std::vector<double> segment_lengths_m = {});

}  // namespace corridor::localizer
