// Stereo visual odometry, one rectified pair at a time: features, left-right matching, temporal
// ZNCC matching with tracks, P3P-RANSAC (or absolute orientation) motion, and local bundle
// adjustment over a sliding window. Frames whose matches collapse are flagged and bridged with the
// previous motion instead of integrating a bad estimate; every frame carries a covariance.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <deque>
#include <future>
#include <opencv2/core.hpp>
#include <unordered_map>
#include <vector>

#include "localizer/vo/feature_detector.hpp"
#include "localizer/vo/kitti_format.hpp"
#include "localizer/vo/local_bundle_adjustment.hpp"
#include "localizer/vo/motion_estimation.hpp"
#include "localizer/vo/stereo_matcher.hpp"
#include "localizer/vo/temporal_matcher.hpp"

namespace corridor::localizer {

struct OdometryOptions {
  DetectorOptions detector;
  StereoMatchOptions stereo;
  TemporalMatchOptions temporal;
  MotionOptions motion;
  MotionModel motion_model = MotionModel::relative;
  bool bundle_adjustment = true;
  BaOptions ba;
  int window_frames = 6;
  double max_speed_mps = 60.0;       // a faster estimated motion is not believed
  double max_rotation_deg = 30.0;    // per frame
  int min_inliers = 20;
  int max_bridged_frames = 5;  // consecutive bad frames before the reference is given up
  // Runs frame k's window adjustment while frame k+1 is matched, and joins it before frame k+1's
  // pose is composed; the result is the same as running it in line, only faster on two cores.
  bool ba_in_background = true;
};

struct FrameReport {
  std::size_t index = 0;
  bool bridged = false;  // matches collapsed: the previous motion was reused
  int features = 0;
  int stereo_points = 0;
  int matches = 0;
  int inliers = 0;
  double motion_rms_px = 0.0;
  double reprojection_before_px = 0.0;  // window BA, before and after
  double reprojection_after_px = 0.0;
  int ba_iterations = 0;
  Matrix6d covariance = Matrix6d::Zero();  // frame-to-frame motion (rotation vector, translation)
  double process_ms = 0.0;
  // Where the time went: detection, stereo matching, temporal matching, motion, bundle adjustment.
  double detect_ms = 0.0, stereo_ms = 0.0, temporal_ms = 0.0, motion_ms = 0.0, ba_ms = 0.0;
};

class StereoOdometry {
 public:
  StereoOdometry(const StereoCamera& camera, const OdometryOptions& options, double frame_rate_hz);

  ~StereoOdometry();
  StereoOdometry(const StereoOdometry&) = delete;
  StereoOdometry& operator=(const StereoOdometry&) = delete;

  // Processes the next pair (8-bit, grey or BGR, same size; std::invalid_argument otherwise) and
  // returns what happened in this frame. With BA in the background, the report's BA fields arrive
  // later, in reports().
  FrameReport process(const cv::Mat& left8, const cv::Mat& right8);

  // Waits for a window adjustment still running and applies it.
  void flush();

  // Camera-to-world of the latest frame; world = the first frame's camera.
  [[nodiscard]] const Pose& pose() const { return trajectory_.back(); }
  // Every frame's pose; those still in the BA window are refined as later frames arrive.
  [[nodiscard]] const std::vector<Pose>& trajectory() const { return trajectory_; }
  [[nodiscard]] const std::vector<FrameReport>& reports() const { return reports_; }

 private:
  struct Observation {
    std::uint64_t track = 0;
    Eigen::Vector2d pixel;
    double right_u = 0.0;  // NaN without a stereo match
    double depth = 0.0;
    Eigen::Vector3d point_cam;
  };
  struct WindowFrame {
    std::size_t index = 0;
    std::vector<Observation> observations;
  };
  struct PreviousFrame {
    FeatureSet features;
    std::vector<std::optional<StereoPoint>> stereo;
    std::vector<std::uint64_t> tracks;
    std::size_t index = 0;
  };

  struct BaJob {
    std::size_t frame = 0;  // the frame whose arrival started it
    std::vector<std::size_t> indices;
    std::vector<BaFrame> frames;
    std::unordered_map<std::uint64_t, Eigen::Vector3d> points;
    std::vector<BaObservation> observations;
    BaReport report;
    double ms = 0.0;
  };
  BaJob prepare_bundle_adjustment(std::size_t frame) const;
  void apply(const BaJob& job);

  StereoCamera camera_;
  OdometryOptions options_;
  FeatureDetector detector_;
  double frame_rate_hz_;
  std::vector<Pose> trajectory_;
  std::vector<FrameReport> reports_;
  std::future<BaJob> pending_;
  std::optional<PreviousFrame> previous_;
  Eigen::Isometry3d last_motion_ = Eigen::Isometry3d::Identity();
  Matrix6d last_covariance_ = Matrix6d::Identity() * 1e-4;
  std::deque<WindowFrame> window_;
  std::uint64_t next_track_ = 1;
  std::uint64_t ransac_seed_ = 1;
};

}  // namespace corridor::localizer
