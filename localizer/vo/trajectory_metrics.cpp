#include "localizer/vo/trajectory_metrics.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace corridor::localizer {
namespace {

double rotation_angle(const Eigen::Matrix3d& r) {
  const double c = std::clamp(0.5 * (r.trace() - 1.0), -1.0, 1.0);
  return std::acos(c);
}

}  // namespace

TrajectoryMetrics evaluate_trajectory(const std::vector<Pose>& est, const std::vector<Pose>& gt,
                                      std::vector<double> lengths) {
  if (est.size() != gt.size()) throw std::invalid_argument("estimate and ground truth differ in frame count");
  TrajectoryMetrics m;
  if (gt.size() < 2) return m;
  if (lengths.empty()) lengths = {100, 200, 300, 400, 500, 600, 700, 800};
  std::vector<double> dist(gt.size(), 0.0);
  for (std::size_t i = 1; i < gt.size(); ++i) {
    dist[i] = dist[i - 1] + (gt[i].translation() - gt[i - 1].translation()).norm();
  }
  m.length_m = dist.back();

  // KITTI devkit: first frames every 10, each length from there, errors per metre.
  double t_sum = 0, r_sum = 0;
  for (const double len : lengths) {
    bool used = false;
    for (std::size_t first = 0; first < gt.size(); first += 10) {
      std::size_t last = first;
      while (last < gt.size() && dist[last] <= dist[first] + len) ++last;
      if (last >= gt.size()) break;
      const Pose delta_gt = gt[first].inverse() * gt[last];
      const Pose delta_est = est[first].inverse() * est[last];
      const Pose error = delta_est.inverse() * delta_gt;
      t_sum += error.translation().norm() / len;
      r_sum += rotation_angle(error.linear()) / len;
      ++m.segments;
      used = true;
    }
    if (used) m.segment_lengths_m.push_back(len);
  }
  if (m.segments > 0) {
    m.t_err_pct = 100.0 * t_sum / m.segments;
    m.r_err_deg_per_100m = 100.0 * (r_sum / m.segments) * 180.0 / std::numbers::pi;
  }

  Eigen::Matrix3Xd src(3, est.size()), dst(3, gt.size());
  for (std::size_t i = 0; i < est.size(); ++i) {
    src.col(static_cast<Eigen::Index>(i)) = est[i].translation();
    dst.col(static_cast<Eigen::Index>(i)) = gt[i].translation();
  }
  const Eigen::Matrix4d align = Eigen::umeyama(src, dst, false);
  double sq = 0;
  for (std::size_t i = 0; i < est.size(); ++i) {
    const Eigen::Vector3d p = align.topLeftCorner<3, 3>() * est[i].translation() + align.topRightCorner<3, 1>();
    sq += (p - gt[i].translation()).squaredNorm();
  }
  m.ate_rmse_m = std::sqrt(sq / static_cast<double>(est.size()));
  m.drift_pct = m.length_m > 0 ? 100.0 * (est.back().translation() - gt.back().translation()).norm() / m.length_m : 0.0;
  return m;
}

}  // namespace corridor::localizer
