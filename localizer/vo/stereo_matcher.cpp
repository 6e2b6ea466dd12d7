#include "localizer/vo/stereo_matcher.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "localizer/vo/zncc.hpp"

namespace corridor::localizer {

std::vector<std::optional<StereoPoint>> match_stereo(const cv::Mat& left, const cv::Mat& right,
                                                     const std::vector<cv::Point2f>& pts, const StereoCamera& camera,
                                                     const StereoMatchOptions& o,
                                                     const std::vector<std::optional<double>>* predicted) {
  std::vector<std::optional<StereoPoint>> out(pts.size());
  const int r = o.patch_radius;
  const int side = 2 * r + 1;
  const double area = static_cast<double>(side * side);
  const int d_min = static_cast<int>(std::floor(camera.focal_baseline() / o.max_depth_m));
  cv::parallel_for_(cv::Range(0, static_cast<int>(pts.size())), [&](const cv::Range& range) {
    cv::Mat templ, strip, patch;
    std::vector<double> col_sum, col_sq, scores;
    for (int i = range.start; i < range.end; ++i) {
      const cv::Point2f p = pts[static_cast<std::size_t>(i)];
      if (p.x - r < 1 || p.y - r < 1 || p.x + r + 1 >= left.cols || p.y + r + 1 >= left.rows) continue;
      // Candidate right centres x − d for d in [d_lo, d_hi], all inside the image.
      int d_lo = std::max(d_min, 0);
      int d_hi = std::min(static_cast<int>(o.max_disparity_px), static_cast<int>(std::floor(p.x)) - r - 1);
      if (predicted && (*predicted)[static_cast<std::size_t>(i)]) {
        const double e = *(*predicted)[static_cast<std::size_t>(i)];
        d_lo = std::max(d_lo, static_cast<int>(std::floor(e - o.predicted_window_px)));
        d_hi = std::min(d_hi, static_cast<int>(std::ceil(e + o.predicted_window_px)));
      }
      if (d_hi - d_lo < 3) continue;
      cv::getRectSubPix(left, {side, side}, p, templ, CV_32F);
      const int width = d_hi - d_lo + side;
      // Strip columns sit at x − d_hi − r + c: the same sub-pixel phase as the template.
      cv::getRectSubPix(right, {width, side}, {p.x - static_cast<float>(d_hi + d_lo) / 2.0f, p.y}, strip, CV_32F);
      const cv::Scalar mean = cv::mean(templ);
      templ -= mean;
      const double t_norm = cv::norm(templ);
      if (t_norm < std::sqrt(area)) continue;  // flat patch
      col_sum.assign(static_cast<std::size_t>(width), 0.0);
      col_sq.assign(static_cast<std::size_t>(width), 0.0);
      for (int y = 0; y < side; ++y) {
        const float* row = strip.ptr<float>(y);
        for (int c = 0; c < width; ++c) {
          col_sum[static_cast<std::size_t>(c)] += row[c];
          col_sq[static_cast<std::size_t>(c)] += static_cast<double>(row[c]) * row[c];
        }
      }
      const int n = d_hi - d_lo + 1;  // candidate j ↔ d = d_hi − j
      scores.assign(static_cast<std::size_t>(n), -1.0);
      double s = 0, q = 0;
      for (int c = 0; c < side; ++c) {
        s += col_sum[static_cast<std::size_t>(c)];
        q += col_sq[static_cast<std::size_t>(c)];
      }
      for (int j = 0; j < n; ++j) {
        if (j > 0) {
          s += col_sum[static_cast<std::size_t>(j + side - 1)] - col_sum[static_cast<std::size_t>(j - 1)];
          q += col_sq[static_cast<std::size_t>(j + side - 1)] - col_sq[static_cast<std::size_t>(j - 1)];
        }
        const double var = q - s * s / area;
        if (var < area) continue;
        double dot = 0;
        for (int y = 0; y < side; ++y) {
          const float* t = templ.ptr<float>(y);
          const float* row = strip.ptr<float>(y) + j;
          for (int c = 0; c < side; ++c) dot += static_cast<double>(t[c]) * row[c];
        }
        scores[static_cast<std::size_t>(j)] = dot / (t_norm * std::sqrt(var));
      }
      const int best = static_cast<int>(std::max_element(scores.begin(), scores.end()) - scores.begin());
      const double top = scores[static_cast<std::size_t>(best)];
      if (!(top >= o.min_score) || best == 0 || best == n - 1) continue;
      double second = -1.0;
      for (int j = 0; j < n; ++j) {
        if (std::abs(j - best) >= 2) second = std::max(second, scores[static_cast<std::size_t>(j)]);
      }
      if (second > top - o.uniqueness_margin) continue;
      const double sub = parabola_peak_offset(scores[static_cast<std::size_t>(best - 1)], top,
                                              scores[static_cast<std::size_t>(best + 1)]);
      // Second fit on half pixels around the first estimate, as in temporal matching: it removes
      // most of the pull towards whole disparities, which would otherwise bias depth and scale.
      const double d1 = (d_hi - best) - sub;
      auto score_at = [&](double d) {
        cv::getRectSubPix(right, {side, side}, {p.x - static_cast<float>(d), p.y}, patch, CV_32F);
        const cv::Scalar m = cv::mean(patch);
        patch -= m;
        const double pn = cv::norm(patch);
        return pn > 0 ? templ.dot(patch) / (t_norm * pn) : -1.0;
      };
      const double d = d1 + 0.5 * parabola_peak_offset(score_at(d1 - 0.5), score_at(d1), score_at(d1 + 0.5));
      if (d < camera.focal_baseline() / o.max_depth_m) continue;
      out[static_cast<std::size_t>(i)] = StereoPoint{d, camera.triangulate(p.x, p.y, d)};
    }
  });
  return out;
}

}  // namespace corridor::localizer
