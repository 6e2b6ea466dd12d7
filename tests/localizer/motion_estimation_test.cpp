#include "localizer/vo/motion_estimation.hpp"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <random>

namespace corridor::localizer {
namespace {

const StereoCamera kCam{700, 700, 320, 240, 0.3};

struct Scene {
  std::vector<Eigen::Vector3d> prev;  // previous camera frame
  std::vector<Eigen::Vector3d> cur;   // current camera frame
  std::vector<Eigen::Vector2d> pixels;
};

Eigen::Isometry3d true_motion() {
  Eigen::Isometry3d m = Eigen::Isometry3d::Identity();
  m.linear() = Eigen::AngleAxisd(0.05, Eigen::Vector3d(0.1, 1.0, 0.05).normalized()).toRotationMatrix();
  m.translation() << 0.12, -0.02, -0.95;  // about 1 m forward: points come closer
  return m;
}

Scene make_scene(int n, double pixel_noise, double outlier_fraction, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> ux(-8, 8), uy(-2, 1.5), uz(4, 35);
  std::normal_distribution<double> noise(0, pixel_noise);
  std::uniform_real_distribution<double> anywhere_u(0, 640), anywhere_v(0, 480), unit(0, 1);
  Scene s;
  const auto m = true_motion();
  while (static_cast<int>(s.prev.size()) < n) {
    const Eigen::Vector3d p(ux(rng), uy(rng), uz(rng));
    const Eigen::Vector3d q = m * p;
    if (q.z() < 2) continue;
    Eigen::Vector2d uv = kCam.project(q) + Eigen::Vector2d(noise(rng), noise(rng));
    Eigen::Vector3d q_obs = q;
    if (unit(rng) < outlier_fraction) {
      uv = {anywhere_u(rng), anywhere_v(rng)};
      q_obs = Eigen::Vector3d(ux(rng), uy(rng), uz(rng));
    }
    s.prev.push_back(p);
    s.cur.push_back(q_obs);
    s.pixels.push_back(uv);
  }
  return s;
}

double rotation_error_deg(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle() * 180 / M_PI;
}

TEST(RelativeOrientation, P3PRansacRecoversTheMotionExactlyWithoutNoise) {
  const auto s = make_scene(80, 0.0, 0.0, 1);
  const auto e = estimate_relative_orientation(s.prev, s.pixels, kCam, {});
  ASSERT_TRUE(e.ok);
  EXPECT_LT((e.motion.translation() - true_motion().translation()).norm(), 1e-6);
  EXPECT_LT(rotation_error_deg(e.motion, true_motion()), 1e-6);
  EXPECT_EQ(e.inliers.size(), 80u);
}

TEST(RelativeOrientation, P3PRansacSeparatesThirtyPercentOutliers) {
  const auto s = make_scene(200, 0.5, 0.3, 2);
  const auto e = estimate_relative_orientation(s.prev, s.pixels, kCam, {});
  ASSERT_TRUE(e.ok);
  EXPECT_LT((e.motion.translation() - true_motion().translation()).norm(), 0.02);
  EXPECT_LT(rotation_error_deg(e.motion, true_motion()), 0.05);
  EXPECT_GT(e.inliers.size(), 120u);
  EXPECT_LT(e.inliers.size(), 150u);
  EXPECT_LT(e.rms_reprojection_px, 1.0);
}

TEST(RelativeOrientation, FailsCleanlyWithTooFewPoints) {
  const auto s = make_scene(5, 0.0, 0.0, 3);
  EXPECT_FALSE(estimate_relative_orientation(s.prev, s.pixels, kCam, {}).ok);
}

TEST(AbsoluteOrientation, UmeyamaRecoversTheMotionFromThreeDPairs) {
  const auto s = make_scene(60, 0.0, 0.0, 4);
  const auto e = estimate_absolute_orientation(s.prev, s.cur, kCam, {});
  ASSERT_TRUE(e.ok);
  EXPECT_LT((e.motion.translation() - true_motion().translation()).norm(), 1e-9);
  EXPECT_LT(rotation_error_deg(e.motion, true_motion()), 1e-9);
}

TEST(AbsoluteOrientation, RansacRejectsOutliers) {
  const auto s = make_scene(200, 0.0, 0.3, 5);
  const auto e = estimate_absolute_orientation(s.prev, s.cur, kCam, {});
  ASSERT_TRUE(e.ok);
  EXPECT_LT((e.motion.translation() - true_motion().translation()).norm(), 1e-6);
  EXPECT_GT(e.inliers.size(), 120u);
}

TEST(MotionCovariance, ShrinksWithMorePointsAndIsPositiveDefinite) {
  const auto few = make_scene(30, 0.5, 0.0, 6);
  const auto many = make_scene(300, 0.5, 0.0, 6);
  const auto c_few = reprojection_covariance(few.prev, few.pixels, true_motion(), kCam);
  const auto c_many = reprojection_covariance(many.prev, many.pixels, true_motion(), kCam);
  EXPECT_GT(c_few.trace(), 2.0 * c_many.trace());
  Eigen::SelfAdjointEigenSolver<Matrix6d> eig(c_many);
  EXPECT_GT(eig.eigenvalues().minCoeff(), 0.0);
  // Forward translation is what stereo constrains least; its sigma stays a few centimetres at most.
  EXPECT_LT(std::sqrt(c_many(5, 5)), 0.05);
}

TEST(MotionModel, ParsesNames) {
  EXPECT_EQ(parse_motion_model("p3p"), MotionModel::relative);
  EXPECT_EQ(parse_motion_model("absolute"), MotionModel::absolute);
  EXPECT_THROW(parse_motion_model("icp"), std::invalid_argument);
}

}  // namespace
}  // namespace corridor::localizer
