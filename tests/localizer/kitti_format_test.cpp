#include "localizer/vo/kitti_format.hpp"

#include <gtest/gtest.h>

#include <unistd.h>

#include <fstream>

#include "localizer/vo/errors.hpp"

namespace corridor::localizer {
namespace {
namespace fs = std::filesystem;

// A fresh directory for one test, removed with everything in it when the test ends.
class TempDir {
 public:
  explicit TempDir(const std::string& name)
      : path_(fs::temp_directory_path() / ("corridor_kitti_" + name + "_" + std::to_string(::getpid()))) {
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ignored;
    fs::remove_all(path_, ignored);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  [[nodiscard]] const fs::path& path() const { return path_; }
  fs::path operator/(const char* file) const { return path_ / file; }

 private:
  fs::path path_;
};

TEST(StereoCamera, TriangulatesDepthFromDisparity) {
  const StereoCamera c{700, 700, 320, 240, 0.3};
  const auto p = c.triangulate(390, 240, 21.0);  // Z = 0.3·700/21 = 10 m; X = 70·10/700 = 1 m
  EXPECT_NEAR(p.z(), 10.0, 1e-12);
  EXPECT_NEAR(p.x(), 1.0, 1e-12);
  EXPECT_NEAR(p.y(), 0.0, 1e-12);
  const auto uv = c.project(p);
  EXPECT_NEAR(uv.x(), 390, 1e-9);
}

TEST(StereoCamera, CalibrationRoundTripsThroughKittiFormat) {
  const TempDir d("calib");
  const StereoCamera c{718.856, 718.856, 607.1928, 185.2157, 0.5371};
  write_kitti_calibration(d / "calib.txt", c);
  const auto r = read_kitti_calibration(d / "calib.txt");
  EXPECT_NEAR(r.fx, c.fx, 1e-9);
  EXPECT_NEAR(r.cy, c.cy, 1e-9);
  EXPECT_NEAR(r.baseline_m, c.baseline_m, 1e-9);
}

TEST(StereoCamera, ReadsTheSharedKittiCalibration) {
  const fs::path f = fs::path(CORRIDOR_SHARED_DATA_DIR) / "stereo/kitti_clip_1/calib.txt";
  if (!fs::exists(f)) GTEST_SKIP() << "shared KITTI clip not present";
  const auto c = read_kitti_calibration(f);
  EXPECT_NEAR(c.fx, 707.09, 0.01);
  EXPECT_NEAR(c.baseline_m, 0.537, 0.001);
}

TEST(StereoCamera, RejectsCalibrationWithoutBaseline) {
  const TempDir d("badcalib");
  std::ofstream(d / "calib.txt") << "P0: 700 0 320 0 0 700 240 0 0 0 1 0\nP1: 700 0 320 0 0 700 240 0 0 0 1 0\n";
  EXPECT_THROW(read_kitti_calibration(d / "calib.txt"), SequenceError);
  std::ofstream(d / "short.txt") << "P0: 700 0 320\n";
  EXPECT_THROW(read_kitti_calibration(d / "short.txt"), SequenceError);
  EXPECT_THROW(read_kitti_calibration(d / "missing.txt"), SequenceError);
}

TEST(KittiPoses, RoundTripKeepsEveryEntry) {
  const TempDir d("poses");
  std::vector<Pose> poses(3, Pose::Identity());
  poses[1].translation() << 1.5, -0.25, 12.0;
  poses[2].linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY()).toRotationMatrix();
  write_kitti_poses(d / "p.txt", poses);
  const auto r = read_kitti_poses(d / "p.txt");
  ASSERT_EQ(r.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) EXPECT_TRUE(r[i].matrix().isApprox(poses[i].matrix(), 1e-8));
}

TEST(KittiPoses, RejectsAShortRow) {
  const TempDir d("badposes");
  std::ofstream(d / "p.txt") << "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1\n";
  EXPECT_THROW(read_kitti_poses(d / "p.txt"), SequenceError);
}

TEST(StereoSequence, ExplainsMissingPartsAndMismatchedCounts) {
  EXPECT_THROW(open_stereo_sequence("/nonexistent/seq"), SequenceError);
  const TempDir d("seq");
  write_kitti_calibration(d / "calib.txt", {700, 700, 320, 240, 0.3});
  EXPECT_THROW(open_stereo_sequence(d.path()), SequenceError);  // no image_0/
  fs::create_directories(d / "image_0");
  fs::create_directories(d / "image_1");
  std::ofstream(d / "image_0/000000.png") << "x";
  std::ofstream(d / "image_0/000001.png") << "x";
  std::ofstream(d / "image_1/000000.png") << "x";
  try {
    open_stereo_sequence(d.path());
    FAIL() << "mismatched counts accepted";
  } catch (const SequenceError& e) {
    EXPECT_NE(std::string(e.what()).find("image_1/ has 1"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace corridor::localizer
