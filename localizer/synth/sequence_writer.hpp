// Writes a synthetic stereo drive to disk in the KITTI odometry layout, with exact ground truth:
// image_0/, image_1/, calib.txt, poses.txt, times.txt, plus drive.csv (the drive in the map frame).
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

#include "localizer/synth/drive_path.hpp"
#include "localizer/synth/stereo_renderer.hpp"
#include "localizer/vo/kitti_format.hpp"

namespace corridor::localizer::synth {

struct ImagingOptions {
  double noise_sigma = 2.0;     // grey levels of Gaussian sensor noise
  double motion_blur = 0.0;     // exposure as a fraction of the frame interval; 0 = sharp
  double exposure_jitter = 0.05;  // relative gain change between frames (auto-exposure)
  std::uint64_t seed = 1;
};

struct SynthSequenceOptions {
  RenderOptions render;
  DriveOptions drive;
  SceneOptions scene;
  ImagingOptions imaging;
  double baseline_m = 0.3;
};

struct SynthSummary {
  std::size_t frames = 0;
  double length_m = 0.0;
  double duration_s = 0.0;
  double total_turn_deg = 0.0;  // sum of |heading change|
};

// The ground-truth pose of the left camera at a drive sample, in the map's 3D frame (east, north, up).
Pose camera_pose_in_map(const DriveSample& sample, double camera_height_m);

// Renders the drive along `polyline` (map frame) into `out_dir`. Throws when the directory cannot
// be written or the polyline is too short.
SynthSummary write_synthetic_sequence(const std::vector<maps::Point2>& polyline, const SynthSequenceOptions& options,
                                      const std::filesystem::path& out_dir);

}  // namespace corridor::localizer::synth
