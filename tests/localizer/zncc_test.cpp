#include "localizer/vo/zncc.hpp"

#include <gtest/gtest.h>

#include <opencv2/core.hpp>

namespace corridor::localizer {
namespace {

cv::Mat random_image(int seed) {
  cv::Mat img(64, 64, CV_8U);
  cv::RNG rng(seed);
  rng.fill(img, cv::RNG::UNIFORM, 0, 256);
  return img;
}

TEST(Zncc, IdenticalPatchesScoreOne) {
  const cv::Mat img = random_image(1);
  const auto a = NormalizedPatch::extract(img, {20, 20}, 5);
  ASSERT_TRUE(a.valid());
  EXPECT_NEAR(a.zncc(a), 1.0f, 1e-5);
}

TEST(Zncc, InvariantToGainAndOffset) {
  const cv::Mat img = random_image(2);
  cv::Mat brighter;
  img.convertTo(brighter, CV_32F, 0.5, 40.0);  // stays inside [0, 255], so no clipping
  brighter.convertTo(brighter, CV_8U);
  const auto a = NormalizedPatch::extract(img, {30, 30}, 5);
  const auto b = NormalizedPatch::extract(brighter, {30, 30}, 5);
  EXPECT_GT(a.zncc(b), 0.99f);  // rounding to 8 bits costs a little
}

TEST(Zncc, InvertedPatchScoresMinusOne) {
  const cv::Mat img = random_image(3);
  const cv::Mat inverted = 255 - img;
  EXPECT_NEAR(NormalizedPatch::extract(img, {20, 20}, 4).zncc(NormalizedPatch::extract(inverted, {20, 20}, 4)), -1.0f,
              1e-5);
}

TEST(Zncc, FlatOrOutsidePatchIsInvalid) {
  const cv::Mat flat(32, 32, CV_8U, cv::Scalar(100));
  EXPECT_FALSE(NormalizedPatch::extract(flat, {16, 16}, 5).valid());
  EXPECT_FALSE(NormalizedPatch::extract(random_image(4), {2, 30}, 5).valid());
  EXPECT_EQ(NormalizedPatch{}.zncc(NormalizedPatch::extract(random_image(4), {30, 30}, 5)), -1.0f);
}

TEST(Zncc, SubpixelExtractionAtIntegerEqualsIntegerExtraction) {
  const cv::Mat img = random_image(5);
  const auto a = NormalizedPatch::extract(img, {25, 27}, 5);
  const auto b = NormalizedPatch::extract_subpixel(img, {25, 27}, 5);
  EXPECT_NEAR(a.zncc(b), 1.0f, 1e-5);
}

TEST(MutualMatching, KeepsOnlyPairsThatChooseEachOther) {
  // a0 likes b0 best, b0 likes a1 best (0.95 > 0.9): a0-b0 is not mutual. a1-b0 is. a2-b1 is.
  const std::vector<Candidate> c = {{0, 0, 0.9f}, {1, 0, 0.95f}, {1, 1, 0.85f}, {2, 1, 0.88f}, {0, 2, 0.5f}};
  const auto m = mutual_best_matches(c, 3, 3, 0.6f);
  ASSERT_EQ(m.size(), 2u);
  EXPECT_EQ(m[0].a, 1);
  EXPECT_EQ(m[0].b, 0);
  EXPECT_EQ(m[1].a, 2);
  EXPECT_EQ(m[1].b, 1);
}

TEST(MutualMatching, DropsMatchesBelowTheScoreFloor) {
  const std::vector<Candidate> c = {{0, 0, 0.7f}};
  EXPECT_TRUE(mutual_best_matches(c, 1, 1, 0.8f).empty());
  EXPECT_EQ(mutual_best_matches(c, 1, 1, 0.6f).size(), 1u);
}

TEST(ParabolaPeak, RecoversTheVertexOfAParabola) {
  // f(x) = 1 − (x − 0.3)²
  auto f = [](double x) { return 1 - (x - 0.3) * (x - 0.3); };
  EXPECT_NEAR(parabola_peak_offset(f(-1), f(0), f(1)), 0.3, 1e-12);
  EXPECT_EQ(parabola_peak_offset(1, 0, 1), 0.0);  // a minimum is not a peak
}

}  // namespace
}  // namespace corridor::localizer
