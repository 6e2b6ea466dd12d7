// KITTI odometry layout on disk: image_0/ (left) and image_1/ (right) PNGs, calib.txt, and poses as
// one row-major 3x4 camera-to-world matrix per line. Reads and writes it, with clear errors.
#pragma once

#include <Eigen/Geometry>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "localizer/vo/stereo_camera.hpp"

namespace corridor::localizer {

using Pose = Eigen::Isometry3d;  // camera-to-world: maps points in the camera frame to the world frame

std::vector<Pose> read_kitti_poses(const std::filesystem::path& file);
void write_kitti_poses(const std::filesystem::path& file, const std::vector<Pose>& poses);

struct StereoSequence {
  std::filesystem::path dir;
  StereoCamera camera;
  std::vector<std::filesystem::path> left;
  std::vector<std::filesystem::path> right;
  std::optional<std::vector<Pose>> ground_truth;  // poses.txt, or poses/XX.txt named after the dir
  double frame_rate_hz = 10.0;                    // from times.txt when present
};

// Opens DIR: checks that both image folders exist with the same frame count and that the ground
// truth, when present, has one pose per frame.
StereoSequence open_stereo_sequence(const std::filesystem::path& dir);

}  // namespace corridor::localizer
