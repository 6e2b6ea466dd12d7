#include "localizer/vo/local_bundle_adjustment.hpp"

#include <gtest/gtest.h>

#include <random>

namespace corridor::localizer {
namespace {

const StereoCamera kCam{700, 700, 320, 240, 0.3};

struct Problem {
  std::vector<BaFrame> truth_frames, frames;
  std::unordered_map<std::uint64_t, Eigen::Vector3d> truth_points, points;
  std::vector<BaObservation> observations;
};

// Five frames driving forward 1 m each, 300 points, 0.3 px noise on observations, and poses and
// points perturbed as frame-to-frame odometry would leave them.
Problem make_problem(std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> ux(-10, 10), uy(-3, 1.5), uz(6, 30);
  std::normal_distribution<double> pix(0, 0.3), pose_noise(0, 0.03), point_noise(0, 0.15);
  Problem p;
  for (int f = 0; f < 5; ++f) {
    BaFrame frame;
    frame.pose.translation() << 0.05 * f, 0, 1.0 * f;
    frame.fixed = f == 0;
    p.truth_frames.push_back(frame);
    BaFrame noisy = frame;
    if (f > 0) {
      noisy.pose.translation() += Eigen::Vector3d(pose_noise(rng), pose_noise(rng), pose_noise(rng)) * f;
      noisy.pose.linear() = Eigen::AngleAxisd(0.002 * f, Eigen::Vector3d::UnitY()).toRotationMatrix();
    }
    p.frames.push_back(noisy);
  }
  for (std::uint64_t t = 1; t <= 300; ++t) {
    const Eigen::Vector3d x(ux(rng), uy(rng), uz(rng) + 5);
    p.truth_points[t] = x;
    p.points[t] = x + Eigen::Vector3d(point_noise(rng), point_noise(rng), point_noise(rng));
    for (int f = 0; f < 5; ++f) {
      const Eigen::Vector3d q = p.truth_frames[static_cast<std::size_t>(f)].pose.inverse() * x;
      const Eigen::Vector2d uv = kCam.project(q);
      const double ur = uv.x() - kCam.focal_baseline() / q.z();
      p.observations.push_back({f, t, uv + Eigen::Vector2d(pix(rng), pix(rng)), ur + pix(rng)});
    }
  }
  return p;
}

double pose_error(const Problem& p) {
  double e = 0;
  for (std::size_t f = 0; f < p.frames.size(); ++f) {
    e += (p.frames[f].pose.translation() - p.truth_frames[f].pose.translation()).norm();
  }
  return e;
}

TEST(BundleAdjustment, ReducesReprojectionErrorAndPoseErrorOnANoisyProblem) {
  auto p = make_problem(1);
  const double before = pose_error(p);
  const BaReport r = bundle_adjust(p.frames, p.points, p.observations, kCam, {});
  ASSERT_TRUE(r.ran);
  EXPECT_LT(r.rms_after_px, 0.5 * r.rms_before_px);
  EXPECT_LT(r.rms_after_px, 0.5);  // close to the 0.3 px noise
  EXPECT_LT(pose_error(p), 0.25 * before);
  EXPECT_GT(r.iterations, 0);
  EXPECT_TRUE(p.frames[0].pose.isApprox(p.truth_frames[0].pose));  // the fixed frame stays put
}

TEST(BundleAdjustment, TrackSelectionRefinesStructureOnlyForLongTracks) {
  auto p = make_problem(2);
  // Tracks 1..100 keep only two views: motion-only points under track selection.
  std::erase_if(p.observations, [](const BaObservation& o) { return o.track <= 100 && o.frame >= 2; });
  auto q = p;
  const auto frozen = p.points.at(7);
  const BaReport selected = bundle_adjust(p.frames, p.points, p.observations, kCam, {});
  EXPECT_EQ(selected.fixed_points, 100);
  EXPECT_EQ(selected.free_points, 200);
  EXPECT_TRUE(p.points.at(7).isApprox(frozen));
  BaOptions all;
  all.track_selection = false;
  const BaReport refined = bundle_adjust(q.frames, q.points, q.observations, kCam, all);
  EXPECT_EQ(refined.fixed_points, 0);
  EXPECT_FALSE(q.points.at(7).isApprox(frozen));
}

}  // namespace
}  // namespace corridor::localizer
