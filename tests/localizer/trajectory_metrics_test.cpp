#include "localizer/vo/trajectory_metrics.hpp"

#include <gtest/gtest.h>

namespace corridor::localizer {
namespace {

std::vector<Pose> straight(int frames, double step_m) {
  std::vector<Pose> poses;
  for (int i = 0; i < frames; ++i) {
    Pose p = Pose::Identity();
    p.translation() << 0, 0, step_m * i;
    poses.push_back(p);
  }
  return poses;
}

TEST(TrajectoryMetrics, PerfectEstimateScoresZero) {
  const auto gt = straight(300, 1.0);
  const auto m = evaluate_trajectory(gt, gt);
  ASSERT_TRUE(m.t_err_pct.has_value());
  EXPECT_NEAR(*m.t_err_pct, 0.0, 1e-12);
  EXPECT_NEAR(*m.r_err_deg_per_100m, 0.0, 1e-6);
  EXPECT_NEAR(m.ate_rmse_m, 0.0, 1e-9);
  EXPECT_NEAR(m.length_m, 299.0, 1e-9);
}

TEST(TrajectoryMetrics, OnePercentScaleErrorGivesOnePercent) {
  const auto gt = straight(500, 1.0);
  const auto est = straight(500, 1.01);
  const auto m = evaluate_trajectory(est, gt);
  EXPECT_NEAR(*m.t_err_pct, 1.0, 0.02);  // segments end at the first frame past the length
  EXPECT_NEAR(m.drift_pct, 1.0, 1e-9);
  EXPECT_EQ(m.segment_lengths_m, (std::vector<double>{100, 200, 300, 400}));
}

TEST(TrajectoryMetrics, HeadingErrorShowsAsRotationError) {
  const auto gt = straight(250, 1.0);
  auto est = gt;
  // A 1 degree yaw error at frame 100 that persists: every segment across it carries 1 degree.
  const Eigen::Matrix3d yaw = Eigen::AngleAxisd(M_PI / 180.0, Eigen::Vector3d::UnitY()).toRotationMatrix();
  for (std::size_t i = 100; i < est.size(); ++i) {
    est[i].linear() = yaw;
    est[i].translation() = est[100].translation() + yaw * (gt[i].translation() - gt[100].translation());
  }
  const auto m = evaluate_trajectory(est, gt, {100});
  EXPECT_GT(*m.r_err_deg_per_100m, 0.3);
  EXPECT_LT(*m.r_err_deg_per_100m, 1.01);
}

TEST(TrajectoryMetrics, ShortDriveHasNoKittiSegmentsButCustomOnesWork) {
  const auto gt = straight(50, 1.0);
  EXPECT_FALSE(evaluate_trajectory(gt, gt).t_err_pct.has_value());
  EXPECT_TRUE(evaluate_trajectory(gt, gt, {10, 20}).t_err_pct.has_value());
  EXPECT_THROW(evaluate_trajectory(gt, straight(49, 1.0)), std::invalid_argument);
}

TEST(TrajectoryMetrics, AteAlignsARigidOffsetAway) {
  const auto gt = straight(100, 1.0);
  auto est = gt;
  for (auto& p : est) p.translation() += Eigen::Vector3d(2, 0, 0);
  EXPECT_NEAR(evaluate_trajectory(est, gt).ate_rmse_m, 0.0, 1e-9);
}

}  // namespace
}  // namespace corridor::localizer
