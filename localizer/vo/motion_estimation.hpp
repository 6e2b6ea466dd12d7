// Frame-to-frame motion from matched features: relative orientation (P3P inside RANSAC on 2D-3D
// correspondences, then Levenberg-Marquardt on the inliers; OpenCV calib3d) or absolute
// orientation (Umeyama/Horn on 3D-3D correspondences inside RANSAC; Eigen), plus the motion's
// covariance from the reprojection Jacobian at the solution.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <optional>
#include <string>
#include <vector>

#include "localizer/vo/stereo_camera.hpp"

namespace corridor::localizer {

enum class MotionModel { relative, absolute };
MotionModel parse_motion_model(const std::string& name);  // "relative" (p3p) or "absolute"
std::string to_string(MotionModel model);

using Matrix6d = Eigen::Matrix<double, 6, 6>;

struct MotionOptions {
  double threshold_normalized = 0.005;  // RANSAC inlier bound in normalized image coordinates
  int iterations = 300;
  double confidence = 0.999;
  int min_inliers = 12;
};

struct MotionEstimate {
  bool ok = false;
  Eigen::Isometry3d motion = Eigen::Isometry3d::Identity();  // maps previous-frame points into the current frame
  std::vector<int> inliers;
  double rms_reprojection_px = 0.0;
  Matrix6d covariance = Matrix6d::Identity();  // over (rotation vector, translation), current frame
};

// points_prev: 3D in the previous left camera frame; pixels_cur: their left-image positions now.
MotionEstimate estimate_relative_orientation(const std::vector<Eigen::Vector3d>& points_prev,
                                             const std::vector<Eigen::Vector2d>& pixels_cur,
                                             const StereoCamera& camera, const MotionOptions& options,
                                             std::uint64_t seed = 1);

// points_cur: the same features triangulated in the current frame. Inliers are judged by the
// stereo reprojection (left u, v and right u) of the moved point, with the same threshold.
MotionEstimate estimate_absolute_orientation(const std::vector<Eigen::Vector3d>& points_prev,
                                             const std::vector<Eigen::Vector3d>& points_cur,
                                             const StereoCamera& camera, const MotionOptions& options,
                                             std::uint64_t seed = 1);

// Gauss-Newton covariance σ²(JᵀJ)⁻¹ of a pose (maps points into the camera) from its reprojection
// residuals; σ² is estimated from the residuals themselves.
Matrix6d reprojection_covariance(const std::vector<Eigen::Vector3d>& points, const std::vector<Eigen::Vector2d>& pixels,
                                 const Eigen::Isometry3d& pose, const StereoCamera& camera);

}  // namespace corridor::localizer
