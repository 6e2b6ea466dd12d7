#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgproc.hpp>

#include "localizer/synth/drive_path.hpp"
#include "localizer/synth/sequence_writer.hpp"
#include "localizer/synth/stereo_renderer.hpp"
#include "localizer/synth/street_scene.hpp"
#include "localizer/vo/feature_detector.hpp"
#include "localizer/vo/stereo_matcher.hpp"

namespace corridor::localizer::synth {
namespace {

std::vector<maps::Point2> l_shape() { return {{0, 0}, {100, 0}, {100, 80}}; }

TEST(DrivePath, SlowsForTheCornerAndKeepsTheFrameRate) {
  DriveOptions o;
  const auto drive = plan_drive(l_shape(), o);
  ASSERT_GT(drive.size(), 100u);
  double fastest = 0, slowest = 1e9;
  for (std::size_t i = 1; i < drive.size(); ++i) {
    EXPECT_NEAR(drive[i].time_s - drive[i - 1].time_s, 0.1, 1e-9);
    const double v = maps::distance_m(drive[i].position, drive[i - 1].position) / 0.1;
    EXPECT_LE(v, o.cruise_speed_mps + 1e-6);
    fastest = std::max(fastest, v);
    slowest = std::min(slowest, v);
  }
  EXPECT_GT(fastest, 9.0);
  EXPECT_LT(slowest, 6.0);  // the rounded 90° corner
  EXPECT_NEAR(drive.front().heading_rad, 0.0, 1e-6);
  EXPECT_NEAR(drive.back().heading_rad, M_PI / 2, 0.05);
}

TEST(DrivePath, RejectsAPolylineTooShortToDrive) {
  EXPECT_THROW(plan_drive({{0, 0}, {5, 0}}, {}), std::invalid_argument);
}

TEST(StreetScene, KeepsFacadesOffTheRoadOnBothSides) {
  const auto line = smooth_polyline(l_shape(), 4.0);
  SceneOptions o;
  const auto scene = build_street_scene(line, o);
  int left = 0, right = 0;
  for (const Wall& w : scene.walls) {
    if (w.texture > 3) continue;  // clutter stands at the kerb
    for (const auto& p : {w.a, w.b}) {
      double d = 1e9;
      for (const auto& c : line) d = std::min(d, maps::distance_m(p, c));
      EXPECT_GT(d, 0.85 * o.min_setback_m);
    }
    (w.a.y_m < 0 || w.a.x_m > 100 ? right : left) += 1;
  }
  EXPECT_GT(left, 5);
  EXPECT_GT(right, 5);
}

TEST(CameraPose, LooksAlongTheHeadingWithYDown) {
  DriveSample s;
  s.position = {3, 4};
  s.heading_rad = M_PI / 2;  // north
  const Pose p = camera_pose_in_map(s, 1.65);
  EXPECT_TRUE((p.linear() * Eigen::Vector3d::UnitZ()).isApprox(Eigen::Vector3d(0, 1, 0), 1e-12));
  EXPECT_TRUE((p.linear() * Eigen::Vector3d::UnitY()).isApprox(Eigen::Vector3d(0, 0, -1), 1e-12));
  EXPECT_TRUE((p.linear() * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d(1, 0, 0), 1e-12));
  EXPECT_NEAR(p.translation().z(), 1.65, 1e-12);
}

// The renderer's geometry checked by stereo: a wall 10 m ahead must show a disparity of f·B/10,
// and the ground at row v must show the disparity of its depth h·f/(v − cy).
TEST(StereoRenderer, RendersGeometryThatStereoMeasuresCorrectly) {
  RenderOptions o;
  const StereoRenderer renderer(o, 3);
  const std::vector<Wall> walls = {{{10, -20}, {10, 20}, 12.0, 0.0, 0, 1.0}};
  const double baseline = 0.3;
  const cv::Mat left_f = renderer.render(walls, {{0, 0}, 0.0});
  const cv::Mat right_f = renderer.render(walls, {{0, -baseline}, 0.0});  // right of an east-facing camera is south
  cv::Mat left, right;
  left_f.convertTo(left, CV_8U);
  right_f.convertTo(right, CV_8U);
  const localizer::StereoCamera cam{o.focal_px, o.focal_px, renderer.cx(), renderer.cy(), baseline};
  // Every detected feature: those above the wall's foot (row cy + h·f/10) lie on the wall, those
  // well below it on the ground.
  const double wall_foot = renderer.cy() + o.camera_height_m * o.focal_px / 10.0;
  std::vector<cv::Point2f> pts;
  for (const auto& k : localizer::detect_features(left, {})) pts.push_back(k.pt);
  const auto m = localizer::match_stereo(left, right, pts, cam, {});
  int wall = 0, wall_ok = 0, ground = 0, ground_ok = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    if (!m[i]) continue;
    if (pts[i].y < wall_foot - 5) {
      ++wall;
      wall_ok += std::abs(m[i]->disparity_px - o.focal_px * baseline / 10.0) < 0.2 ? 1 : 0;
    } else if (pts[i].y > wall_foot + 10) {
      ++ground;
      const double depth = o.camera_height_m * o.focal_px / (pts[i].y - renderer.cy());
      ground_ok += std::abs(m[i]->point.z() - depth) < 0.03 * depth ? 1 : 0;
    }
  }
  EXPECT_GT(wall, 100);
  EXPECT_GT(ground, 50);
  EXPECT_GT(wall_ok, 0.95 * wall);
  EXPECT_GT(ground_ok, 0.9 * ground);
}

}  // namespace
}  // namespace corridor::localizer::synth
