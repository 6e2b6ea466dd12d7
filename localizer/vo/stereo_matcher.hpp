// Left-right matching along the epipolar row of a rectified pair, giving each left keypoint a
// sub-pixel disparity and a 3D point (Z = B·f/d), or none when the match is ambiguous or too far.
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <optional>
#include <vector>

#include "localizer/vo/stereo_camera.hpp"

namespace corridor::localizer {

struct StereoMatchOptions {
  int patch_radius = 4;
  double max_disparity_px = 160.0;
  double max_depth_m = 40.0;  // beyond this, stereo depth is too uncertain to use
  float min_score = 0.85f;
  float uniqueness_margin = 0.03f;  // the best peak must beat any other peak (2+ px away) by this
  double predicted_window_px = 8.0;  // search half-width around a predicted disparity
};

struct StereoPoint {
  double disparity_px = 0.0;
  Eigen::Vector3d point;  // left camera frame
};

// Left points may be sub-pixel: both patches are resampled at the point's row. `predicted`, when
// given, holds an expected disparity per point (from a track's previous depth) that narrows the
// search; points without one search the whole range.
std::vector<std::optional<StereoPoint>> match_stereo(const cv::Mat& left8, const cv::Mat& right8,
                                                     const std::vector<cv::Point2f>& left_points,
                                                     const StereoCamera& camera, const StereoMatchOptions& options,
                                                     const std::vector<std::optional<double>>* predicted = nullptr);

}  // namespace corridor::localizer
