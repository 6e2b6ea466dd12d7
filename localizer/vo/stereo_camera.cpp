#include "localizer/vo/stereo_camera.hpp"

#include <array>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include "localizer/vo/errors.hpp"

namespace corridor::localizer {

Eigen::Vector3d StereoCamera::triangulate(double u, double v, double disparity_px) const {
  const double z = depth_from_disparity(disparity_px);
  return {(u - cx) * z / fx, (v - cy) * z / fy, z};
}

Eigen::Vector2d StereoCamera::project(const Eigen::Vector3d& p_cam) const {
  return {fx * p_cam.x() / p_cam.z() + cx, fy * p_cam.y() / p_cam.z() + cy};
}

StereoCamera read_kitti_calibration(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw SequenceError("cannot open calibration file " + file.string());
  std::map<std::string, std::array<double, 12>> rows;
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream ls(line);
    std::string key;
    if (!(ls >> key) || key.empty() || key.back() != ':') continue;
    std::array<double, 12> p{};
    for (double& x : p) {
      if (!(ls >> x)) throw SequenceError(file.string() + ": row " + key + " must hold 12 numbers");
    }
    rows[key.substr(0, key.size() - 1)] = p;
  }
  if (!rows.contains("P0") || !rows.contains("P1")) {
    throw SequenceError(file.string() + ": needs rows P0 and P1 (KITTI odometry calib.txt)");
  }
  const auto& p0 = rows["P0"];
  const auto& p1 = rows["P1"];
  StereoCamera c{p0[0], p0[5], p0[2], p0[6], -p1[3] / p1[0]};
  if (!(c.fx > 0 && c.fy > 0 && std::isfinite(c.cx) && std::isfinite(c.cy))) {
    throw SequenceError(file.string() + ": P0 has no positive focal length");
  }
  if (!(c.baseline_m > 0 && std::isfinite(c.baseline_m))) {
    throw SequenceError(file.string() + ": P1's translation gives no positive baseline (expect P1[3] = -fx*B)");
  }
  return c;
}

void write_kitti_calibration(const std::filesystem::path& file, const StereoCamera& c) {
  std::ofstream out(file);
  if (!out) throw SequenceError("cannot write " + file.string());
  out.precision(12);
  auto row = [&](const char* name, double tx) {
    out << name << ": " << c.fx << " 0 " << c.cx << ' ' << tx << " 0 " << c.fy << ' ' << c.cy << " 0 0 0 1 0\n";
  };
  row("P0", 0.0);
  row("P1", -c.fx * c.baseline_m);
}

}  // namespace corridor::localizer
