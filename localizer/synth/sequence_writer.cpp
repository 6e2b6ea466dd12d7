#include "localizer/synth/sequence_writer.hpp"

#include <spdlog/spdlog.h>

#include <cmath>
#include <fstream>
#include <numbers>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>

#include "localizer/vo/errors.hpp"

namespace corridor::localizer::synth {
namespace fs = std::filesystem;

Pose camera_pose_in_map(const DriveSample& s, double camera_height_m) {
  const double dx = std::cos(s.heading_rad), dy = std::sin(s.heading_rad);
  Pose p = Pose::Identity();
  // Columns: the camera's x (right), y (down) and z (forward) axes in east-north-up.
  p.linear() << dy, 0, dx,  //
      -dx, 0, dy,           //
      0, -1, 0;
  p.translation() = Eigen::Vector3d(s.position.x_m, s.position.y_m, camera_height_m);
  return p;
}

namespace {

DriveSample interpolate(const std::vector<DriveSample>& drive, std::size_t k, double offset_frames) {
  // Poses between frames, for motion blur.
  const double pos = std::clamp(static_cast<double>(k) + offset_frames, 0.0, static_cast<double>(drive.size() - 1));
  const std::size_t i = std::min(static_cast<std::size_t>(pos), drive.size() - 2);
  const double f = pos - static_cast<double>(i);
  const DriveSample& a = drive[i];
  const DriveSample& b = drive[i + 1];
  double dh = b.heading_rad - a.heading_rad;
  while (dh > std::numbers::pi) dh -= 2 * std::numbers::pi;
  while (dh < -std::numbers::pi) dh += 2 * std::numbers::pi;
  DriveSample s = a;
  s.time_s = a.time_s + f * (b.time_s - a.time_s);
  s.position = {a.position.x_m + f * (b.position.x_m - a.position.x_m), a.position.y_m + f * (b.position.y_m - a.position.y_m)};
  s.heading_rad = a.heading_rad + f * dh;
  return s;
}

}  // namespace

SynthSummary write_synthetic_sequence(const std::vector<maps::Point2>& polyline, const SynthSequenceOptions& o,
                                      const fs::path& out_dir) {
  const auto drive = plan_drive(polyline, o.drive);
  if (drive.size() < 2) throw SequenceError("the drive is too short to render");
  SceneOptions scene_options = o.scene;
  scene_options.drive_duration_s = drive.back().time_s;
  const StreetScene scene =
      build_street_scene(smooth_polyline(polyline, o.drive.corner_smoothing_m), scene_options);
  const StereoRenderer renderer(o.render, o.scene.seed ^ 0x5eedULL);

  std::error_code ec;
  fs::create_directories(out_dir / "image_0", ec);
  fs::create_directories(out_dir / "image_1", ec);
  if (ec || !fs::is_directory(out_dir / "image_1")) throw SequenceError("cannot create " + out_dir.string());

  const StereoCamera camera{o.render.focal_px, o.render.focal_px, renderer.cx(), renderer.cy(), o.baseline_m};
  write_kitti_calibration(out_dir / "calib.txt", camera);

  std::mt19937_64 rng(o.imaging.seed);
  std::normal_distribution<double> gain_step(0.0, o.imaging.exposure_jitter);
  double gain = 1.0;
  const int blur_samples = o.imaging.motion_blur > 0 ? 5 : 1;
  const Pose first = camera_pose_in_map(drive.front(), o.render.camera_height_m);
  std::vector<Pose> poses;
  std::ofstream times(out_dir / "times.txt"), csv(out_dir / "drive.csv");
  csv << "frame,time_s,x_m,y_m,heading_rad,arc_m\n";
  SynthSummary summary;
  for (std::size_t k = 0; k < drive.size(); ++k) {
    cv::Mat left = cv::Mat::zeros(o.render.height, o.render.width, CV_32F);
    cv::Mat right = left.clone();
    for (int b = 0; b < blur_samples; ++b) {
      const double offset = blur_samples == 1 ? 0.0 : o.imaging.motion_blur * (b / (blur_samples - 1.0) - 0.5);
      const DriveSample s = interpolate(drive, k, offset);
      const auto walls = scene.walls_at(s.time_s);
      const double rx = std::sin(s.heading_rad), ry = -std::cos(s.heading_rad);
      left += renderer.render(walls, {s.position, s.heading_rad});
      right += renderer.render(
          walls, {{s.position.x_m + o.baseline_m * rx, s.position.y_m + o.baseline_m * ry}, s.heading_rad});
    }
    // Auto-exposure drifts slowly around 1; both cameras share it, as a synchronized rig would.
    gain = std::clamp(gain + gain_step(rng) - 0.2 * (gain - 1.0), 0.7, 1.3);
    for (cv::Mat* img : {&left, &right}) {
      *img *= gain / blur_samples;
      if (o.imaging.noise_sigma > 0) {
        cv::Mat noise(img->size(), CV_32F);
        cv::randn(noise, 0.0, o.imaging.noise_sigma);
        *img += noise;
      }
    }
    cv::Mat left8, right8;
    left.convertTo(left8, CV_8U);
    right.convertTo(right8, CV_8U);
    char name[32];
    std::snprintf(name, sizeof name, "%06zu.png", k);
    if (!cv::imwrite((out_dir / "image_0" / name).string(), left8) ||
        !cv::imwrite((out_dir / "image_1" / name).string(), right8)) {
      throw SequenceError("cannot write images into " + out_dir.string());
    }
    poses.push_back(first.inverse() * camera_pose_in_map(drive[k], o.render.camera_height_m));
    times << drive[k].time_s << '\n';
    csv << k << ',' << drive[k].time_s << ',' << drive[k].position.x_m << ',' << drive[k].position.y_m << ','
        << drive[k].heading_rad << ',' << drive[k].arc_m << '\n';
    if (k > 0) {
      double dh = drive[k].heading_rad - drive[k - 1].heading_rad;
      dh = std::remainder(dh, 2 * std::numbers::pi);
      summary.total_turn_deg += std::abs(dh) * 180.0 / std::numbers::pi;
    }
    if (k % 100 == 0) spdlog::info("vo synth: frame {} of {}", k, drive.size());
  }
  write_kitti_poses(out_dir / "poses.txt", poses);
  summary.frames = drive.size();
  summary.length_m = drive.back().arc_m - drive.front().arc_m;
  summary.duration_s = drive.back().time_s;
  return summary;
}

}  // namespace corridor::localizer::synth
