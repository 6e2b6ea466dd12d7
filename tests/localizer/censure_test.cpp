#include "localizer/vo/censure.hpp"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "localizer/vo/feature_detector.hpp"

namespace corridor::localizer {
namespace {

TEST(CenSurE, ResponseIsMeanInsideMinusMeanOfTheRing) {
  cv::Mat img(40, 40, CV_8U);
  cv::RNG(7).fill(img, cv::RNG::UNIFORM, 0, 256);
  cv::Mat ii;
  cv::integral(img, ii, CV_32S);
  const int x = 20, y = 18, n = 3;
  double in = 0, ring = 0;
  int n_in = 0, n_ring = 0;
  for (int yy = y - 2 * n; yy <= y + 2 * n; ++yy) {
    for (int xx = x - 2 * n; xx <= x + 2 * n; ++xx) {
      const bool inner = std::abs(xx - x) <= n && std::abs(yy - y) <= n;
      (inner ? in : ring) += img.at<std::uint8_t>(yy, xx);
      ++(inner ? n_in : n_ring);
    }
  }
  EXPECT_NEAR(censure_response(ii, x, y, n), in / n_in - ring / n_ring, 1e-3);
}

TEST(CenSurE, FlatImageHasNoKeypoints) {
  const cv::Mat flat(120, 160, CV_8U, cv::Scalar(90));
  EXPECT_TRUE(detect_censure(flat, {}).empty());
}

TEST(CenSurE, FindsABlobAtItsCentreAndScale) {
  cv::Mat img(120, 160, CV_8U, cv::Scalar(40));
  cv::rectangle(img, cv::Rect(77, 57, 7, 7), cv::Scalar(220), cv::FILLED);  // centre (80, 60), side 7 = 2n+1, n = 3
  const auto kps = detect_censure(img, {});
  ASSERT_FALSE(kps.empty());
  const auto best = *std::max_element(kps.begin(), kps.end(),
                                      [](const cv::KeyPoint& a, const cv::KeyPoint& b) { return a.response < b.response; });
  EXPECT_NEAR(best.pt.x, 80, 1.0);
  EXPECT_NEAR(best.pt.y, 60, 1.0);
  EXPECT_EQ(best.octave, 3);
}

TEST(CenSurE, RejectsResponsesAlongAStraightEdge) {
  // A long bright bar: its ends are corners, but the middle of the bar is a line.
  // Slight noise along it gives the bar's middle local maxima that only the line test removes.
  cv::Mat img(120, 200, CV_8U, cv::Scalar(40));
  cv::rectangle(img, cv::Rect(30, 57, 140, 7), cv::Scalar(200), cv::FILLED);
  cv::Mat noise(120, 200, CV_8U);
  cv::RNG(5).fill(noise, cv::RNG::UNIFORM, 0, 12);
  img += noise;
  for (const auto& kp : detect_censure(img, {})) {
    EXPECT_TRUE(kp.pt.x < 60 || kp.pt.x > 140) << "keypoint on the line at x=" << kp.pt.x;
  }
  CenSurEOptions no_line_test;
  no_line_test.line_threshold = 1e6f;
  bool any_middle = false;
  for (const auto& kp : detect_censure(img, no_line_test)) any_middle |= kp.pt.x >= 60 && kp.pt.x <= 140;
  EXPECT_TRUE(any_middle) << "without the line test the bar's middle should respond";
}

TEST(FeatureDetector, EveryDetectorSpreadsFeaturesOverTheGrid) {
  cv::Mat img(240, 320, CV_8U);
  cv::RNG(3).fill(img, cv::RNG::UNIFORM, 0, 256);
  cv::GaussianBlur(img, img, {0, 0}, 1.5);
  for (const auto kind : {DetectorKind::censure, DetectorKind::fast, DetectorKind::harris}) {
    DetectorOptions o;
    o.kind = kind;
    o.max_features = 200;
    o.grid_cols = 4;
    o.grid_rows = 2;
    const auto kps = detect_features(img, o);
    EXPECT_GT(kps.size(), 100u) << to_string(kind);
    EXPECT_LE(kps.size(), 200u) << to_string(kind);
    int left = 0;
    for (const auto& k : kps) left += k.pt.x < 160 ? 1 : 0;
    EXPECT_GT(left, static_cast<int>(kps.size()) / 4) << to_string(kind);
  }
}

TEST(FeatureDetector, ParsesNamesAndRejectsUnknownOnes) {
  EXPECT_EQ(parse_detector_kind("fast"), DetectorKind::fast);
  EXPECT_THROW(parse_detector_kind("star"), std::invalid_argument);
}

}  // namespace
}  // namespace corridor::localizer
