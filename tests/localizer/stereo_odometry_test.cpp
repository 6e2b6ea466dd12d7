#include "localizer/vo/stereo_odometry.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <opencv2/imgcodecs.hpp>

#include "localizer/synth/sequence_writer.hpp"
#include "localizer/vo/trajectory_metrics.hpp"

namespace corridor::localizer {
namespace {
namespace fs = std::filesystem;

// One short synthetic drive with a 90° bend, rendered once for the whole suite.
class StereoOdometryOnSynthetic : public ::testing::Test {
 protected:
  // Rendered once per build tree and shared by every test process: into a private directory first,
  // then renamed into place, so parallel test processes never see half a sequence.
  static void SetUpTestSuite() {
    const fs::path dir = fs::path(CORRIDOR_TEST_DATA_DIR) / "vo_bend_v1";
    if (!fs::exists(dir / "poses.txt")) {
      const fs::path tmp = dir.string() + ".tmp" + std::to_string(::getpid());
      fs::remove_all(tmp);
      synth::SynthSequenceOptions o;
      o.scene.seed = 11;
      o.imaging.seed = 11;
      o.drive.max_length_m = 90;
      synth::write_synthetic_sequence({{0, 0}, {50, 0}, {50, 60}}, o, tmp);
      std::error_code ec;
      fs::rename(tmp, dir, ec);
      if (ec) fs::remove_all(tmp);  // another process got there first
    }
    sequence_ = new StereoSequence(open_stereo_sequence(dir));
  }
  static void TearDownTestSuite() { delete sequence_; }

  static std::vector<FrameReport> run(StereoOdometry& vo, int black_frame = -1) {
    for (std::size_t i = 0; i < sequence_->left.size(); ++i) {
      cv::Mat l = cv::imread(sequence_->left[i].string(), cv::IMREAD_GRAYSCALE);
      cv::Mat r = cv::imread(sequence_->right[i].string(), cv::IMREAD_GRAYSCALE);
      if (static_cast<int>(i) == black_frame) {
        l.setTo(0);
        r.setTo(0);
      }
      vo.process(l, r);
    }
    vo.flush();
    return vo.reports();
  }

  static inline StereoSequence* sequence_ = nullptr;
};

TEST_F(StereoOdometryOnSynthetic, StaysWithinTheDriftBoundThroughABend) {
  StereoOdometry vo(sequence_->camera, {}, sequence_->frame_rate_hz);
  const auto reports = run(vo);
  const auto m = evaluate_trajectory(vo.trajectory(), *sequence_->ground_truth, {10, 20, 40});
  EXPECT_GT(m.length_m, 80.0);
  EXPECT_LT(m.drift_pct, 1.0);
  EXPECT_LT(*m.t_err_pct, 1.0);
  EXPECT_LT(m.ate_rmse_m, 0.3);
  int ba_frames = 0;
  double before = 0, after = 0;
  for (const auto& r : reports) {
    EXPECT_FALSE(r.bridged) << "frame " << r.index;
    if (r.index > 0) {
      EXPECT_GT(r.inliers, 50) << "frame " << r.index;
    }
    if (r.ba_iterations > 0) {
      ++ba_frames;
      before += r.reprojection_before_px;
      after += r.reprojection_after_px;
    }
  }
  EXPECT_GT(ba_frames, static_cast<int>(reports.size()) / 2);
  EXPECT_LT(after, before);
}

TEST_F(StereoOdometryOnSynthetic, BackgroundBundleAdjustmentGivesTheSameTrajectoryAsInline) {
  OdometryOptions inline_ba;
  inline_ba.ba_in_background = false;
  StereoOdometry a(sequence_->camera, {}, sequence_->frame_rate_hz);
  StereoOdometry b(sequence_->camera, inline_ba, sequence_->frame_rate_hz);
  run(a);
  run(b);
  ASSERT_EQ(a.trajectory().size(), b.trajectory().size());
  for (std::size_t i = 0; i < a.trajectory().size(); ++i) {
    EXPECT_TRUE(a.trajectory()[i].isApprox(b.trajectory()[i], 1e-12)) << "frame " << i;
  }
}

TEST_F(StereoOdometryOnSynthetic, BridgesABlackFrameInsteadOfIntegratingIt) {
  StereoOdometry vo(sequence_->camera, {}, sequence_->frame_rate_hz);
  const auto reports = run(vo, 40);
  EXPECT_TRUE(reports[40].bridged);
  EXPECT_GT(reports[40].covariance.trace(), 50 * reports[39].covariance.trace());
  EXPECT_FALSE(reports[41].bridged) << "frame 41 should match against frame 39";
  const auto m = evaluate_trajectory(vo.trajectory(), *sequence_->ground_truth, {10, 20, 40});
  EXPECT_LT(m.drift_pct, 2.0);
}

TEST_F(StereoOdometryOnSynthetic, AbsoluteOrientationAlsoTracksTheDrive) {
  OdometryOptions o;
  o.motion_model = MotionModel::absolute;
  o.bundle_adjustment = false;
  StereoOdometry vo(sequence_->camera, o, sequence_->frame_rate_hz);
  run(vo);
  const auto m = evaluate_trajectory(vo.trajectory(), *sequence_->ground_truth, {10, 20, 40});
  EXPECT_LT(m.drift_pct, 5.0);
}

TEST(StereoOdometry, RejectsAPairOfDifferentSizes) {
  StereoOdometry vo({700, 700, 320, 240, 0.3}, {}, 10.0);
  const cv::Mat left(480, 640, CV_8U, cv::Scalar(0)), right(240, 320, CV_8U, cv::Scalar(0));
  EXPECT_THROW(vo.process(left, right), std::invalid_argument);
  EXPECT_TRUE(vo.trajectory().empty());
}

}  // namespace
}  // namespace corridor::localizer
