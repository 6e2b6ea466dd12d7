#include "localizer/vo/kitti_format.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "localizer/vo/errors.hpp"

namespace corridor::localizer {
namespace fs = std::filesystem;

std::vector<Pose> read_kitti_poses(const fs::path& file) {
  std::ifstream in(file);
  if (!in) throw SequenceError("cannot open pose file " + file.string());
  std::vector<Pose> poses;
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    std::istringstream ls(line);
    Eigen::Matrix<double, 3, 4> m;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c) {
        if (!(ls >> m(r, c)) || !std::isfinite(m(r, c))) {
          throw SequenceError(file.string() + ":" + std::to_string(line_no) + ": expected 12 finite numbers");
        }
      }
    }
    Pose p = Pose::Identity();
    p.linear() = m.leftCols<3>();
    p.translation() = m.col(3);
    poses.push_back(p);
  }
  return poses;
}

void write_kitti_poses(const fs::path& file, const std::vector<Pose>& poses) {
  std::ofstream out(file);
  if (!out) throw SequenceError("cannot write " + file.string());
  out.precision(9);
  for (const Pose& p : poses) {
    const Eigen::Matrix<double, 3, 4> m = p.matrix().topRows<3>();
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c) out << m(r, c) << ((r == 2 && c == 3) ? '\n' : ' ');
    }
  }
}

namespace {

std::vector<fs::path> list_images(const fs::path& dir) {
  if (!fs::is_directory(dir)) throw SequenceError("missing image folder " + dir.string());
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(dir)) {
    const auto ext = entry.path().extension().string();
    if (entry.is_regular_file() && (ext == ".png" || ext == ".jpg" || ext == ".pgm")) files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

}  // namespace

StereoSequence open_stereo_sequence(const fs::path& dir) {
  if (!fs::is_directory(dir)) throw SequenceError("sequence directory " + dir.string() + " does not exist");
  StereoSequence s;
  s.dir = dir;
  s.camera = read_kitti_calibration(dir / "calib.txt");
  s.left = list_images(dir / "image_0");
  s.right = list_images(dir / "image_1");
  if (s.left.empty()) throw SequenceError(dir.string() + ": image_0/ holds no images");
  if (s.left.size() != s.right.size()) {
    throw SequenceError(dir.string() + ": image_0/ has " + std::to_string(s.left.size()) + " images but image_1/ has " +
                        std::to_string(s.right.size()));
  }
  fs::path gt = dir / "poses.txt";
  if (!fs::exists(gt)) gt = dir / "poses" / (dir.filename().string() + ".txt");
  if (fs::exists(gt)) {
    s.ground_truth = read_kitti_poses(gt);
    if (s.ground_truth->size() != s.left.size()) {
      throw SequenceError(gt.string() + " has " + std::to_string(s.ground_truth->size()) + " poses for " +
                          std::to_string(s.left.size()) + " frames");
    }
  }
  if (std::ifstream times(dir / "times.txt"); times) {
    double t0 = 0, t1 = 0;
    if ((times >> t0 >> t1) && t1 > t0) s.frame_rate_hz = 1.0 / (t1 - t0);
  }
  return s;
}

}  // namespace corridor::localizer
