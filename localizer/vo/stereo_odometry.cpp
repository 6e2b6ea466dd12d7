#include "localizer/vo/stereo_odometry.hpp"

#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <opencv2/imgproc.hpp>

namespace corridor::localizer {
namespace {

cv::Mat to_grey(const cv::Mat& image) {
  if (image.channels() == 1) return image;
  cv::Mat grey;
  cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  return grey;
}

}  // namespace

StereoOdometry::StereoOdometry(const StereoCamera& camera, const OdometryOptions& options, double frame_rate_hz)
    : camera_(camera), options_(options), detector_(options.detector), frame_rate_hz_(frame_rate_hz) {}

StereoOdometry::~StereoOdometry() {
  if (pending_.valid()) pending_.wait();
}

void StereoOdometry::flush() {
  if (pending_.valid()) apply(pending_.get());
}

FrameReport StereoOdometry::process(const cv::Mat& left_in, const cv::Mat& right_in) {
  const auto t0 = std::chrono::steady_clock::now();
  auto lap = [last = t0]() mutable {
    const auto now = std::chrono::steady_clock::now();
    const double ms = std::chrono::duration<double, std::milli>(now - last).count();
    last = now;
    return ms;
  };
  FrameReport report;
  report.index = trajectory_.size();
  const cv::Mat left = to_grey(left_in);
  const cv::Mat right = to_grey(right_in);
  if (left.size() != right.size() || left.depth() != CV_8U) {
    throw std::invalid_argument("stereo odometry needs two 8-bit images of the same size");
  }

  const auto keypoints = detector_.detect(left);
  std::vector<cv::Point2f> points;
  points.reserve(keypoints.size());
  for (const auto& k : keypoints) points.push_back(k.pt);
  FeatureSet current = describe_features(left, points, options_.temporal.patch_radius);
  report.features = static_cast<int>(points.size());
  std::vector<std::uint64_t> tracks(points.size(), 0);
  report.detect_ms = lap();

  std::vector<TemporalMatch> matches;
  MotionEstimate estimate;
  // Frames since the reference: more than one after a bridged frame, which never becomes one.
  const std::size_t gap = previous_ ? report.index - previous_->index : 0;
  Eigen::Isometry3d predicted_motion = Eigen::Isometry3d::Identity();
  for (std::size_t k = 0; k < gap; ++k) predicted_motion = last_motion_ * predicted_motion;
  if (previous_) {
    // Predict where each previous feature lands under the previous motion (constant velocity).
    std::vector<cv::Point2f> predicted(previous_->features.points.size());
    for (std::size_t i = 0; i < predicted.size(); ++i) {
      predicted[i] = previous_->features.points[i];
      if (const auto& s = previous_->stereo[i]) {
        const Eigen::Vector3d q = predicted_motion * s->point;
        if (q.z() > 0.5) {
          const auto uv = camera_.project(q);
          predicted[i] = {static_cast<float>(uv.x()), static_cast<float>(uv.y())};
        }
      }
    }
    matches = match_temporal(previous_->features, predicted, current, left, options_.temporal);
    report.matches = static_cast<int>(matches.size());
    // A matched feature continues its track at the sub-pixel position of the previous patch.
    for (const auto& m : matches) {
      const auto j = static_cast<std::size_t>(m.current);
      current.points[j] = m.refined;
      current.patches[j] = NormalizedPatch::extract_subpixel(left, m.refined, options_.temporal.patch_radius);
    }
  }
  report.temporal_ms = lap();
  // A tracked feature's depth is predicted from its previous depth under the previous motion.
  std::vector<std::optional<double>> expected(current.points.size());
  for (const auto& m : matches) {
    if (const auto& sp = previous_->stereo[static_cast<std::size_t>(m.previous)]) {
      const Eigen::Vector3d q = predicted_motion * sp->point;
      if (q.z() > 0.5) expected[static_cast<std::size_t>(m.current)] = camera_.focal_baseline() / q.z();
    }
  }
  const auto stereo = match_stereo(left, right, current.points, camera_, options_.stereo, &expected);
  for (const auto& s : stereo) report.stereo_points += s.has_value() ? 1 : 0;
  report.stereo_ms = lap();

  Eigen::Isometry3d motion = Eigen::Isometry3d::Identity();
  std::vector<int> used;  // indices into matches that the motion explains
  if (previous_) {
    std::vector<Eigen::Vector3d> prev_points, cur_points;
    std::vector<Eigen::Vector2d> cur_pixels;
    std::vector<int> match_of;
    for (int k = 0; k < static_cast<int>(matches.size()); ++k) {
      const auto& m = matches[static_cast<std::size_t>(k)];
      const auto& sp = previous_->stereo[static_cast<std::size_t>(m.previous)];
      if (!sp) continue;
      const auto& sc = stereo[static_cast<std::size_t>(m.current)];
      if (options_.motion_model == MotionModel::absolute && !sc) continue;
      prev_points.push_back(sp->point);
      cur_pixels.emplace_back(m.refined.x, m.refined.y);
      if (sc) cur_points.push_back(sc->point);
      match_of.push_back(k);
    }
    const std::uint64_t seed = ransac_seed_++;
    estimate = options_.motion_model == MotionModel::relative
                   ? estimate_relative_orientation(prev_points, cur_pixels, camera_, options_.motion, seed)
                   : estimate_absolute_orientation(prev_points, cur_points, camera_, options_.motion, seed);
    const double max_step = options_.max_speed_mps / frame_rate_hz_ * static_cast<double>(gap);
    const double angle_deg = Eigen::AngleAxisd(estimate.motion.linear()).angle() * 180.0 / std::numbers::pi;
    const bool plausible = estimate.ok && static_cast<int>(estimate.inliers.size()) >= options_.min_inliers &&
                           estimate.motion.translation().norm() < max_step &&
                           angle_deg < options_.max_rotation_deg * static_cast<double>(gap);
    if (plausible) {
      motion = estimate.motion;
      report.inliers = static_cast<int>(estimate.inliers.size());
      report.motion_rms_px = estimate.rms_reprojection_px;
      report.covariance = estimate.covariance;
      for (const int i : estimate.inliers) used.push_back(match_of[static_cast<std::size_t>(i)]);
      last_covariance_ = estimate.covariance;
    } else {
      // Bridge: keep the previous motion, say how little we know, and keep the last good frame
      // as the reference for the next one.
      report.bridged = true;
      report.covariance = last_covariance_ * 100.0;
    }
    for (const int k : used) {
      const auto& m = matches[static_cast<std::size_t>(k)];
      tracks[static_cast<std::size_t>(m.current)] = previous_->tracks[static_cast<std::size_t>(m.previous)];
    }
  }
  for (auto& t : tracks) {
    if (t == 0) t = next_track_++;
  }

  flush();  // the previous frame's window adjustment refines the pose this one builds on
  Pose pose = Pose::Identity();
  if (previous_ && report.bridged) {
    pose = trajectory_.back() * last_motion_.inverse();
  } else if (previous_) {
    pose = trajectory_[previous_->index] * motion.inverse();
    if (gap == 1) last_motion_ = motion;
  }
  trajectory_.push_back(pose);
  if (report.bridged) {
    reports_.push_back(report);
    // After too many bad frames in a row the old reference is out of sight: start over from here.
    if (gap >= static_cast<std::size_t>(options_.max_bridged_frames)) {
      window_.clear();
      previous_ = PreviousFrame{std::move(current), stereo, std::move(tracks), report.index};
    }
    FrameReport& stored = reports_[report.index];
    stored.process_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    return stored;
  }

  WindowFrame frame;
  frame.index = report.index;
  for (std::size_t j = 0; j < current.points.size(); ++j) {
    if (!stereo[j]) continue;  // the window keeps stereo observations: they fix scale and structure
    Observation ob;
    ob.track = tracks[j];
    ob.pixel = {current.points[j].x, current.points[j].y};
    ob.right_u = current.points[j].x - stereo[j]->disparity_px;
    ob.depth = stereo[j]->point.z();
    ob.point_cam = stereo[j]->point;
    frame.observations.push_back(ob);
  }
  report.motion_ms = lap();
  window_.push_back(std::move(frame));
  while (static_cast<int>(window_.size()) > options_.window_frames) window_.pop_front();
  reports_.push_back(report);
  if (options_.bundle_adjustment && previous_ && window_.size() >= 3) {
    auto job = prepare_bundle_adjustment(report.index);
    auto run = [this, job = std::move(job)]() mutable {
      const auto start = std::chrono::steady_clock::now();
      job.report = bundle_adjust(job.frames, job.points, job.observations, camera_, options_.ba);
      job.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
      return std::move(job);
    };
    pending_ = std::async(options_.ba_in_background ? std::launch::async : std::launch::deferred, std::move(run));
    if (!options_.ba_in_background) flush();
  }
  previous_ = PreviousFrame{std::move(current), stereo, std::move(tracks), report.index};
  FrameReport& stored = reports_[report.index];
  stored.process_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return stored;
}

StereoOdometry::BaJob StereoOdometry::prepare_bundle_adjustment(std::size_t frame) const {
  BaJob job;
  job.frame = frame;
  std::unordered_map<std::uint64_t, int> views;
  for (const auto& f : window_) {
    for (const auto& ob : f.observations) ++views[ob.track];
  }
  // Each point starts from its nearest stereo view (the most accurate depth) in the window, but
  // never from the newest frame: a point fixed where the newest pose put it would only pin that
  // pose to its own first estimate.
  std::unordered_map<std::uint64_t, std::pair<double, Eigen::Vector3d>> seed;
  for (std::size_t w = 0; w < window_.size(); ++w) {
    const auto& f = window_[w];
    job.indices.push_back(f.index);
    job.frames.push_back({trajectory_[f.index], w == 0});
    const bool newest = w + 1 == window_.size();
    for (const auto& ob : f.observations) {
      if (views[ob.track] < 2) continue;
      job.observations.push_back({static_cast<int>(w), ob.track, ob.pixel, ob.right_u});
      if (newest) continue;
      auto it = seed.find(ob.track);
      if (it == seed.end() || ob.depth < it->second.first) {
        seed[ob.track] = {ob.depth, trajectory_[f.index] * ob.point_cam};
      }
    }
  }
  for (const auto& [track, sd] : seed) job.points[track] = sd.second;
  return job;
}

void StereoOdometry::apply(const BaJob& job) {
  FrameReport& report = reports_[job.frame];
  const BaReport& ba = job.report;
  report.reprojection_before_px = ba.rms_before_px;
  report.reprojection_after_px = ba.ran ? ba.rms_after_px : ba.rms_before_px;
  report.ba_iterations = ba.iterations;
  report.ba_ms = job.ms;
  if (!ba.ran || !(ba.rms_after_px <= ba.rms_before_px)) return;
  for (std::size_t w = 0; w < job.indices.size(); ++w) trajectory_[job.indices[w]] = job.frames[w].pose;
}

}  // namespace corridor::localizer
