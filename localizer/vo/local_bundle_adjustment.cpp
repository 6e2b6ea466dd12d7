#include "localizer/vo/local_bundle_adjustment.hpp"

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include <array>
#include <cmath>

namespace corridor::localizer {
namespace {

struct Intrinsics {
  double fx, fy, cx, cy, baseline;
};

// Residuals of one observation; pose = (angle-axis, translation) of world-to-camera.
template <bool kStereo>
struct Reprojection {
  Intrinsics k;
  double u, v, ur;
  template <typename T>
  bool operator()(const T* pose, const T* point, T* r) const {
    T p[3];
    ceres::AngleAxisRotatePoint(pose, point, p);
    p[0] += pose[3];
    p[1] += pose[4];
    p[2] += pose[5];
    if (p[2] < T(1e-3)) return false;  // behind the camera: this step is rejected
    const T iz = T(1.0) / p[2];
    r[0] = T(k.fx) * p[0] * iz + T(k.cx) - T(u);
    r[1] = T(k.fy) * p[1] * iz + T(k.cy) - T(v);
    if constexpr (kStereo) r[2] = T(k.fx) * (p[0] - T(k.baseline)) * iz + T(k.cx) - T(ur);
    return true;
  }
};

std::array<double, 6> to_params(const Eigen::Isometry3d& camera_to_world) {
  const Eigen::Isometry3d w2c = camera_to_world.inverse();
  const Eigen::AngleAxisd aa(w2c.linear());
  const Eigen::Vector3d r = aa.axis() * aa.angle();
  return {r.x(), r.y(), r.z(), w2c.translation().x(), w2c.translation().y(), w2c.translation().z()};
}

Eigen::Isometry3d from_params(const std::array<double, 6>& p) {
  const Eigen::Vector3d r(p[0], p[1], p[2]);
  const double angle = r.norm();
  Eigen::Isometry3d w2c = Eigen::Isometry3d::Identity();
  if (angle > 1e-15) w2c.linear() = Eigen::AngleAxisd(angle, r / angle).toRotationMatrix();
  w2c.translation() << p[3], p[4], p[5];
  return w2c.inverse();
}

double squared_error(const std::vector<BaFrame>& frames, const std::unordered_map<std::uint64_t, Eigen::Vector3d>& points,
                     const std::vector<BaObservation>& obs, const StereoCamera& c, int& count) {
  std::vector<Eigen::Isometry3d> world_to_camera;
  world_to_camera.reserve(frames.size());
  for (const auto& f : frames) world_to_camera.push_back(f.pose.inverse());
  double sq = 0;
  count = 0;
  for (const auto& o : obs) {
    const auto it = points.find(o.track);
    if (it == points.end()) continue;
    const Eigen::Vector3d q = world_to_camera[static_cast<std::size_t>(o.frame)] * it->second;
    if (q.z() <= 1e-3) continue;
    const Eigen::Vector2d uv = c.project(q);
    sq += (uv - o.pixel).squaredNorm();
    count += 2;
    if (std::isfinite(o.right_u)) {
      const double e = uv.x() - c.focal_baseline() / q.z() - o.right_u;
      sq += e * e;
      count += 1;
    }
  }
  return sq;
}

}  // namespace

BaReport bundle_adjust(std::vector<BaFrame>& frames, std::unordered_map<std::uint64_t, Eigen::Vector3d>& points,
                       const std::vector<BaObservation>& obs, const StereoCamera& c, const BaOptions& o) {
  BaReport report;
  int count = 0;
  report.rms_before_px = std::sqrt(squared_error(frames, points, obs, c, count) / std::max(count, 1));
  if (frames.size() < 2 || obs.empty()) return report;

  std::unordered_map<std::uint64_t, int> views;
  for (const auto& ob : obs) ++views[ob.track];

  std::vector<std::array<double, 6>> params;
  params.reserve(frames.size());
  for (const auto& f : frames) params.push_back(to_params(f.pose));
  std::unordered_map<std::uint64_t, std::array<double, 3>> pt;
  for (const auto& [track, p] : points) pt[track] = {p.x(), p.y(), p.z()};

  ceres::Problem problem;
  const Intrinsics k{c.fx, c.fy, c.cx, c.cy, c.baseline_m};
  for (const auto& ob : obs) {
    auto it = pt.find(ob.track);
    if (it == pt.end()) continue;
    auto* loss = new ceres::HuberLoss(o.huber_px);
    double* pose = params[static_cast<std::size_t>(ob.frame)].data();
    if (std::isfinite(ob.right_u)) {
      auto* cost = new ceres::AutoDiffCostFunction<Reprojection<true>, 3, 6, 3>(
          new Reprojection<true>{k, ob.pixel.x(), ob.pixel.y(), ob.right_u});
      problem.AddResidualBlock(cost, loss, pose, it->second.data());
    } else {
      auto* cost = new ceres::AutoDiffCostFunction<Reprojection<false>, 2, 6, 3>(
          new Reprojection<false>{k, ob.pixel.x(), ob.pixel.y(), 0.0});
      problem.AddResidualBlock(cost, loss, pose, it->second.data());
    }
  }
  for (std::size_t f = 0; f < frames.size(); ++f) {
    if (frames[f].fixed && problem.HasParameterBlock(params[f].data())) problem.SetParameterBlockConstant(params[f].data());
  }
  for (auto& [track, p] : pt) {
    if (!problem.HasParameterBlock(p.data())) continue;
    const bool refine_structure = !o.track_selection || views[track] >= o.min_views_for_structure;
    if (refine_structure) {
      ++report.free_points;
    } else {
      problem.SetParameterBlockConstant(p.data());
      ++report.fixed_points;
    }
  }

  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_SCHUR;
  options.max_num_iterations = o.max_iterations;
  options.num_threads = 1;
  options.logging_type = ceres::SILENT;
  options.minimizer_progress_to_stdout = false;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  report.ran = true;
  report.iterations = static_cast<int>(summary.iterations.size()) - 1;
  if (!summary.IsSolutionUsable()) return report;

  for (std::size_t f = 0; f < frames.size(); ++f) {
    if (!frames[f].fixed) frames[f].pose = from_params(params[f]);
  }
  for (auto& [track, p] : pt) points[track] = Eigen::Vector3d(p[0], p[1], p[2]);
  report.rms_after_px = std::sqrt(squared_error(frames, points, obs, c, count) / std::max(count, 1));
  return report;
}

}  // namespace corridor::localizer
