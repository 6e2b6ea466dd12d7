#include "localizer/vo/stereo_matcher.hpp"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "localizer/vo/temporal_matcher.hpp"

namespace corridor::localizer {
namespace {

cv::Mat textured(int w, int h, int seed) {
  cv::Mat img(h, w, CV_8U);
  cv::RNG(seed).fill(img, cv::RNG::UNIFORM, 0, 256);
  cv::GaussianBlur(img, img, {0, 0}, 1.2);
  cv::normalize(img, img, 0, 255, cv::NORM_MINMAX);
  return img;
}

cv::Mat shifted(const cv::Mat& img, double dx, double dy) {
  cv::Mat out;
  const cv::Matx23d m(1, 0, dx, 0, 1, dy);
  cv::warpAffine(img, out, m, img.size(), cv::INTER_CUBIC, cv::BORDER_REFLECT);
  return out;
}

TEST(StereoMatcher, RecoversAKnownSubpixelDisparityAndDepth) {
  const StereoCamera cam{700, 700, 160, 120, 0.3};
  const cv::Mat left = textured(320, 240, 1);
  const double d = 12.3;  // right image: the scene moves left by d
  const cv::Mat right = shifted(left, -d, 0);
  const std::vector<cv::Point2f> pts = {{150, 100}, {200.4f, 140.7f}, {260, 60}};
  const auto out = match_stereo(left, right, pts, cam, {});
  for (std::size_t i = 0; i < pts.size(); ++i) {
    ASSERT_TRUE(out[i].has_value()) << i;
    EXPECT_NEAR(out[i]->disparity_px, d, 0.1) << i;
    EXPECT_NEAR(out[i]->point.z(), 700 * 0.3 / d, 0.15) << i;
  }
}

TEST(StereoMatcher, RejectsPointsBeyondTheDepthLimit) {
  const StereoCamera cam{700, 700, 160, 120, 0.3};
  const cv::Mat left = textured(320, 240, 2);
  const cv::Mat right = shifted(left, -3.0, 0);  // Z = 70 m
  StereoMatchOptions o;
  o.max_depth_m = 40.0;  // needs d ≥ 5.25
  EXPECT_FALSE(match_stereo(left, right, {{200, 100}}, cam, o)[0].has_value());
  o.max_depth_m = 100.0;
  EXPECT_TRUE(match_stereo(left, right, {{200, 100}}, cam, o)[0].has_value());
}

TEST(StereoMatcher, RejectsAnAmbiguousRepeatingPattern) {
  // Vertical stripes with an 8 px period: every 8 px along the row looks the same.
  cv::Mat left(240, 320, CV_8U);
  for (int x = 0; x < 320; ++x) left.col(x).setTo(x % 8 < 4 ? 40 : 200);
  cv::GaussianBlur(left, left, {0, 0}, 1.0);
  const StereoCamera cam{700, 700, 160, 120, 0.3};
  EXPECT_FALSE(match_stereo(left, shifted(left, -10, 0), {{200, 100}}, cam, {})[0].has_value());
}

TEST(TemporalMatcher, MatchesShiftedFeaturesMutuallyWithSubpixelPositions) {
  const cv::Mat a = textured(320, 240, 5);
  const cv::Mat b = shifted(a, 7.4, -3.3);
  std::vector<cv::Point2f> pa, pb;
  for (int y = 30; y < 210; y += 30) {
    for (int x = 30; x < 290; x += 30) {
      pa.emplace_back(static_cast<float>(x), static_cast<float>(y));
      pb.emplace_back(static_cast<float>(x + 7), static_cast<float>(y - 3));  // as a detector would find them
    }
  }
  const auto fa = describe_features(a, pa, 5);
  const auto fb = describe_features(b, pb, 5);
  const auto matches = match_temporal(fa, pa, fb, b, {});
  EXPECT_GT(matches.size(), pa.size() * 8 / 10);
  for (const auto& m : matches) {
    EXPECT_EQ(m.previous, m.current);
    EXPECT_NEAR(m.refined.x - pa[static_cast<std::size_t>(m.previous)].x, 7.4, 0.15);
    EXPECT_NEAR(m.refined.y - pa[static_cast<std::size_t>(m.previous)].y, -3.3, 0.15);
  }
}

}  // namespace
}  // namespace corridor::localizer
