// The rectified stereo rig: one pinhole model shared by both cameras, and the baseline between them.
#pragma once

#include <Eigen/Core>
#include <filesystem>

namespace corridor::localizer {

struct StereoCamera {
  double fx = 0.0;
  double fy = 0.0;
  double cx = 0.0;
  double cy = 0.0;
  double baseline_m = 0.0;  // right camera sits at +baseline along the left camera's x axis

  [[nodiscard]] double focal_baseline() const { return fx * baseline_m; }
  // Depth from disparity: Z = B·f/d.
  [[nodiscard]] double depth_from_disparity(double disparity_px) const { return focal_baseline() / disparity_px; }
  // The 3D point, in the left camera frame (x right, y down, z forward), seen at (u, v) with disparity d.
  [[nodiscard]] Eigen::Vector3d triangulate(double u, double v, double disparity_px) const;
  [[nodiscard]] Eigen::Vector2d project(const Eigen::Vector3d& p_cam) const;
};

// Reads a KITTI odometry calib.txt (rows "P0: 12 numbers", "P1: ..."). P1's tx = -fx·B gives B.
StereoCamera read_kitti_calibration(const std::filesystem::path& file);
void write_kitti_calibration(const std::filesystem::path& file, const StereoCamera& camera);

}  // namespace corridor::localizer
