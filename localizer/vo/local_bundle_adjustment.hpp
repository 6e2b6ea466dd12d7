// Local sparse bundle adjustment over a sliding window of keyframes (Ceres, robust Huber loss).
// Stereo observations constrain left u, v and right u. With track selection (the seed thesis's
// rule), only points seen in more than 3 views are refined; shorter tracks keep their triangulated
// position and refine the motion alone.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "localizer/vo/stereo_camera.hpp"

namespace corridor::localizer {

struct BaFrame {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();  // camera-to-world
  bool fixed = false;
};

struct BaObservation {
  int frame = 0;  // index into the frames
  std::uint64_t track = 0;
  Eigen::Vector2d pixel;         // left image
  double right_u = 0.0;          // right image column; NaN for a left-only observation
};

struct BaOptions {
  int max_iterations = 8;
  double huber_px = 1.0;
  bool track_selection = true;
  int min_views_for_structure = 4;  // "more than 3 views"
};

struct BaReport {
  bool ran = false;
  double rms_before_px = 0.0;
  double rms_after_px = 0.0;
  int iterations = 0;
  int free_points = 0;
  int fixed_points = 0;
};

// Refines `frames` (the non-fixed ones) and `points` (world frame) in place. Observations of tracks
// missing from `points` are ignored.
BaReport bundle_adjust(std::vector<BaFrame>& frames, std::unordered_map<std::uint64_t, Eigen::Vector3d>& points,
                       const std::vector<BaObservation>& observations, const StereoCamera& camera,
                       const BaOptions& options);

}  // namespace corridor::localizer
