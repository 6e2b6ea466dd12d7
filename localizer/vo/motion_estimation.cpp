#include "localizer/vo/motion_estimation.hpp"

#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <random>
#include <stdexcept>

namespace corridor::localizer {

MotionModel parse_motion_model(const std::string& name) {
  if (name == "relative" || name == "p3p") return MotionModel::relative;
  if (name == "absolute") return MotionModel::absolute;
  throw std::invalid_argument("motion model must be relative (P3P) or absolute, got '" + name + "'");
}

std::string to_string(MotionModel m) { return m == MotionModel::relative ? "relative" : "absolute"; }

namespace {

cv::Matx33d camera_matrix(const StereoCamera& c) { return {c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1}; }

Eigen::Isometry3d from_cv(const cv::Mat& rvec, const cv::Mat& tvec) {
  cv::Mat r;
  cv::Rodrigues(rvec, r);
  Eigen::Matrix3d re;
  cv::cv2eigen(r, re);
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = re;
  t.translation() << tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2);
  return t;
}

double reprojection_error_px(const Eigen::Isometry3d& m, const Eigen::Vector3d& p, const Eigen::Vector2d& px,
                             const StereoCamera& c) {
  const Eigen::Vector3d q = m * p;
  if (q.z() <= 0.1) return 1e9;
  return (c.project(q) - px).norm();
}

MotionEstimate finish(const Eigen::Isometry3d& motion, const std::vector<Eigen::Vector3d>& pts,
                      const std::vector<Eigen::Vector2d>& px, const StereoCamera& c, double threshold_px,
                      int min_inliers) {
  MotionEstimate e;
  e.motion = motion;
  double sq = 0;
  std::vector<Eigen::Vector3d> in_pts;
  std::vector<Eigen::Vector2d> in_px;
  for (int i = 0; i < static_cast<int>(pts.size()); ++i) {
    const double err = reprojection_error_px(motion, pts[static_cast<std::size_t>(i)], px[static_cast<std::size_t>(i)], c);
    if (err < threshold_px) {
      e.inliers.push_back(i);
      sq += err * err;
      in_pts.push_back(pts[static_cast<std::size_t>(i)]);
      in_px.push_back(px[static_cast<std::size_t>(i)]);
    }
  }
  e.ok = static_cast<int>(e.inliers.size()) >= min_inliers;
  if (!e.inliers.empty()) e.rms_reprojection_px = std::sqrt(sq / static_cast<double>(e.inliers.size()));
  if (e.ok) e.covariance = reprojection_covariance(in_pts, in_px, motion, c);
  return e;
}

}  // namespace

MotionEstimate estimate_relative_orientation(const std::vector<Eigen::Vector3d>& pts,
                                             const std::vector<Eigen::Vector2d>& px, const StereoCamera& c,
                                             const MotionOptions& o, std::uint64_t seed) {
  if (pts.size() != px.size()) throw std::invalid_argument("points and pixels differ in count");
  if (static_cast<int>(pts.size()) < std::max(4, o.min_inliers)) return {};
  std::vector<cv::Point3d> obj;
  std::vector<cv::Point2d> img;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    obj.emplace_back(pts[i].x(), pts[i].y(), pts[i].z());
    img.emplace_back(px[i].x(), px[i].y());
  }
  const double threshold_px = o.threshold_normalized * c.fx;
  cv::Mat rvec, tvec;
  std::vector<int> inliers;
  cv::theRNG().state = seed;  // RANSAC sampling is reproducible run to run
  const bool found = cv::solvePnPRansac(obj, img, camera_matrix(c), cv::noArray(), rvec, tvec, false, o.iterations,
                                        static_cast<float>(threshold_px), o.confidence, inliers, cv::SOLVEPNP_P3P);
  if (!found || static_cast<int>(inliers.size()) < o.min_inliers) return {};
  // Refine on RANSAC's inliers, then once more on the inliers of the refined motion; finish()
  // reports the inliers of the final one.
  for (int pass = 0; pass < 2; ++pass) {
    if (pass == 1) {
      const auto m = from_cv(rvec, tvec);
      inliers.clear();
      for (int i = 0; i < static_cast<int>(pts.size()); ++i) {
        if (reprojection_error_px(m, pts[static_cast<std::size_t>(i)], px[static_cast<std::size_t>(i)], c) < threshold_px) {
          inliers.push_back(i);
        }
      }
    }
    std::vector<cv::Point3d> o_in;
    std::vector<cv::Point2d> i_in;
    for (const int i : inliers) {
      o_in.push_back(obj[static_cast<std::size_t>(i)]);
      i_in.push_back(img[static_cast<std::size_t>(i)]);
    }
    if (static_cast<int>(o_in.size()) < o.min_inliers) return {};
    cv::solvePnPRefineLM(o_in, i_in, camera_matrix(c), cv::noArray(), rvec, tvec);
  }
  return finish(from_cv(rvec, tvec), pts, px, c, threshold_px, o.min_inliers);
}

MotionEstimate estimate_absolute_orientation(const std::vector<Eigen::Vector3d>& prev,
                                             const std::vector<Eigen::Vector3d>& cur, const StereoCamera& c,
                                             const MotionOptions& o, std::uint64_t seed) {
  if (prev.size() != cur.size()) throw std::invalid_argument("point sets differ in count");
  const int n = static_cast<int>(prev.size());
  if (n < std::max(3, o.min_inliers)) return {};
  const double threshold_px = o.threshold_normalized * c.fx;
  std::vector<Eigen::Vector2d> px(prev.size());
  std::vector<double> right_u(prev.size());
  for (std::size_t i = 0; i < cur.size(); ++i) {
    px[i] = c.project(cur[i]);
    right_u[i] = px[i].x() - c.focal_baseline() / cur[i].z();
  }
  auto stereo_inlier = [&](const Eigen::Isometry3d& m, int i) {
    const Eigen::Vector3d q = m * prev[static_cast<std::size_t>(i)];
    if (q.z() <= 0.1) return false;
    const Eigen::Vector2d uv = c.project(q);
    const double ur = uv.x() - c.focal_baseline() / q.z();
    return (uv - px[static_cast<std::size_t>(i)]).norm() < threshold_px &&
           std::abs(ur - right_u[static_cast<std::size_t>(i)]) < threshold_px;
  };
  auto fit = [&](const std::vector<int>& idx) {
    Eigen::Matrix3Xd src(3, idx.size()), dst(3, idx.size());
    for (std::size_t k = 0; k < idx.size(); ++k) {
      src.col(static_cast<Eigen::Index>(k)) = prev[static_cast<std::size_t>(idx[k])];
      dst.col(static_cast<Eigen::Index>(k)) = cur[static_cast<std::size_t>(idx[k])];
    }
    Eigen::Isometry3d m;
    m.matrix() = Eigen::umeyama(src, dst, false);
    return m;
  };
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> pick(0, n - 1);
  std::vector<int> best;
  int iterations = o.iterations;
  for (int it = 0; it < iterations; ++it) {
    int a = pick(rng), b = pick(rng), d = pick(rng);
    if (a == b || b == d || a == d) continue;
    const auto m = fit({a, b, d});
    std::vector<int> in;
    for (int i = 0; i < n; ++i) {
      if (stereo_inlier(m, i)) in.push_back(i);
    }
    if (in.size() > best.size()) {
      best = std::move(in);
      // Adaptive stop, as OpenCV's RANSAC does: enough samples for the inlier ratio seen so far.
      const double w = static_cast<double>(best.size()) / n;
      const double needed = std::log(1 - o.confidence) / std::log(std::max(1e-12, 1 - w * w * w));
      iterations = std::min(o.iterations, static_cast<int>(std::ceil(needed)) + 1);
    }
  }
  if (static_cast<int>(best.size()) < o.min_inliers) return {};
  // Least squares in 3D on the inliers: the weakness of absolute orientation is here, since far
  // points' depth errors weigh as much as near points'.
  Eigen::Isometry3d m = fit(best);
  std::vector<int> in;
  for (int i = 0; i < n; ++i) {
    if (stereo_inlier(m, i)) in.push_back(i);
  }
  if (static_cast<int>(in.size()) >= o.min_inliers) m = fit(in);
  return finish(m, prev, px, c, threshold_px, o.min_inliers);
}

Matrix6d reprojection_covariance(const std::vector<Eigen::Vector3d>& points, const std::vector<Eigen::Vector2d>& pixels,
                                 const Eigen::Isometry3d& pose, const StereoCamera& c) {
  // Left-perturbation: q = exp(δ)·pose·p, δ = (ω, τ); ∂q/∂ω = −[q]×, ∂q/∂τ = I.
  Matrix6d jtj = Matrix6d::Zero();
  double sq = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d q = pose * points[i];
    const double iz = 1.0 / q.z();
    Eigen::Matrix<double, 2, 3> dpi;
    dpi << c.fx * iz, 0, -c.fx * q.x() * iz * iz, 0, c.fy * iz, -c.fy * q.y() * iz * iz;
    Eigen::Matrix<double, 3, 6> dq;
    Eigen::Matrix3d skew;
    skew << 0, -q.z(), q.y(), q.z(), 0, -q.x(), -q.y(), q.x(), 0;
    dq.leftCols<3>() = -skew;
    dq.rightCols<3>() = Eigen::Matrix3d::Identity();
    const Eigen::Matrix<double, 2, 6> j = dpi * dq;
    jtj += j.transpose() * j;
    sq += (c.project(q) - pixels[i]).squaredNorm();
  }
  const double dof = std::max(1.0, 2.0 * static_cast<double>(points.size()) - 6.0);
  const double sigma2 = std::max(sq / dof, 0.01);  // never claim better than 0.1 px
  return sigma2 * jtj.completeOrthogonalDecomposition().pseudoInverse();
}

}  // namespace corridor::localizer
