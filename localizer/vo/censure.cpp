#include "localizer/vo/censure.hpp"

#include <cmath>
#include <opencv2/imgproc.hpp>

namespace corridor::localizer {
namespace {

struct BoxWeights {
  float inner;  // weight of the inner box sum
  float outer;  // weight of the whole outer box sum
};

// mean(inner) − mean(ring) = in·(1/a_in + 1/a_ring) − all/a_ring: zero on a flat image, the
// paper's zero-DC condition.
BoxWeights weights(int n) {
  const double a_in = (2.0 * n + 1) * (2.0 * n + 1);
  const double a_all = (4.0 * n + 1) * (4.0 * n + 1);
  const double a_ring = a_all - a_in;
  return {static_cast<float>(1.0 / a_in + 1.0 / a_ring), static_cast<float>(1.0 / a_ring)};
}

inline int box_sum(const cv::Mat& ii, int x0, int y0, int x1, int y1) {
  return ii.at<int>(y1 + 1, x1 + 1) - ii.at<int>(y0, x1 + 1) - ii.at<int>(y1 + 1, x0) + ii.at<int>(y0, x0);
}

inline double box_sum_d(const cv::Mat& ii, int x0, int y0, int x1, int y1) {
  return ii.at<double>(y1 + 1, x1 + 1) - ii.at<double>(y0, x1 + 1) - ii.at<double>(y1 + 1, x0) + ii.at<double>(y0, x0);
}

}  // namespace

float censure_response(const cv::Mat& ii, int x, int y, int n) {
  const BoxWeights w = weights(n);
  const int in = box_sum(ii, x - n, y - n, x + n, y + n);
  const int all = box_sum(ii, x - 2 * n, y - 2 * n, x + 2 * n, y + 2 * n);
  return w.inner * static_cast<float>(in) - w.outer * static_cast<float>(all);
}

std::vector<cv::KeyPoint> CenSurEDetector::detect(const cv::Mat& image8) {
  CV_Assert(image8.type() == CV_8UC1);
  const CenSurEOptions& o = options_;
  const int w = image8.cols, h = image8.rows;
  const int scales = std::max(1, o.max_scale);
  const int border = 2 * scales + 2;
  std::vector<cv::KeyPoint> out;
  if (w <= 2 * border || h <= 2 * border) return out;
  cv::integral(image8, integral_, CV_32S);
  responses_.resize(static_cast<std::size_t>(scales));
  for (auto& r : responses_) {
    // Zeroed once: the border is never written, and later frames of the same size reuse the maps.
    if (r.rows != h || r.cols != w) r = cv::Mat::zeros(h, w, CV_32F);
  }

  cv::parallel_for_(cv::Range(0, scales * 4), [&](const cv::Range& jobs) {
    for (int job = jobs.start; job < jobs.end; ++job) {
      // Each scale's rows in four bands, so both cores stay busy.
      const int n = job / 4 + 1, band = job % 4;
      cv::Mat& r = responses_[static_cast<std::size_t>(n - 1)];
      const BoxWeights wt = weights(n);
      const int y_begin = border + (h - 2 * border) * band / 4, y_end = border + (h - 2 * border) * (band + 1) / 4;
      for (int y = y_begin; y < y_end; ++y) {
        const int* i0 = integral_.ptr<int>(y - n);
        const int* i1 = integral_.ptr<int>(y + n + 1);
        const int* o0 = integral_.ptr<int>(y - 2 * n);
        const int* o1 = integral_.ptr<int>(y + 2 * n + 1);
        auto* row = r.ptr<float>(y);
        for (int x = border; x < w - border; ++x) {
          const int in = i1[x + n + 1] - i0[x + n + 1] - i1[x - n] + i0[x - n];
          const int all = o1[x + 2 * n + 1] - o0[x + 2 * n + 1] - o1[x - 2 * n] + o0[x - 2 * n];
          row[x] = wt.inner * static_cast<float>(in) - wt.outer * static_cast<float>(all);
        }
      }
    }
  });

  cv::Sobel(image8, gx_, CV_32F, 1, 0, 3);
  cv::Sobel(image8, gy_, CV_32F, 0, 1, 3);
  cv::multiply(gx_, gx_, product_);
  cv::integral(product_, ixx_, CV_64F);
  cv::multiply(gy_, gy_, product_);
  cv::integral(product_, iyy_, CV_64F);
  cv::multiply(gx_, gy_, product_);
  cv::integral(product_, ixy_, CV_64F);
  const double line_limit = (o.line_threshold + 1.0) * (o.line_threshold + 1.0) / o.line_threshold;

  // Extrema over the 3×3×3 neighbourhood in position and scale; the same scale is checked first
  // because it rejects most pixels. Row bands run in parallel and are merged in order.
  constexpr int kBands = 8;
  std::vector<std::vector<cv::KeyPoint>> found(kBands);
  cv::parallel_for_(cv::Range(0, kBands), [&](const cv::Range& bands) {
    for (int band = bands.start; band < bands.end; ++band) {
      const int y_begin = border + (h - 2 * border) * band / kBands;
      const int y_end = border + (h - 2 * border) * (band + 1) / kBands;
      auto& mine = found[static_cast<std::size_t>(band)];
      for (int s = 0; s < scales; ++s) {
        const int n = s + 1;
        for (int y = y_begin; y < y_end; ++y) {
          const float* row = responses_[static_cast<std::size_t>(s)].ptr<float>(y);
          for (int x = border; x < w - border; ++x) {
            const float v = row[x];
            if (std::abs(v) < o.response_threshold) continue;
            const bool is_max = v > 0;
            auto beaten = [&](int t, bool skip_centre) {
              const cv::Mat& q = responses_[static_cast<std::size_t>(t)];
              for (int dy = -1; dy <= 1; ++dy) {
                const float* qr = q.ptr<float>(y + dy);
                for (int dx = -1; dx <= 1; ++dx) {
                  if (skip_centre && dx == 0 && dy == 0) continue;
                  if (is_max ? qr[x + dx] >= v : qr[x + dx] <= v) return true;
                }
              }
              return false;
            };
            if (beaten(s, true) || (s > 0 && beaten(s - 1, false)) || (s + 1 < scales && beaten(s + 1, false))) continue;
            // Line test: second-moment matrix of the gradients over a window growing with the scale.
            const int rad = 2 * n;
            const double sxx = box_sum_d(ixx_, x - rad, y - rad, x + rad, y + rad);
            const double syy = box_sum_d(iyy_, x - rad, y - rad, x + rad, y + rad);
            const double sxy = box_sum_d(ixy_, x - rad, y - rad, x + rad, y + rad);
            const double det = sxx * syy - sxy * sxy;
            const double trace = sxx + syy;
            if (det <= 0 || trace * trace / det >= line_limit) continue;
            mine.emplace_back(cv::Point2f(static_cast<float>(x), static_cast<float>(y)), static_cast<float>(4 * n + 1),
                              -1.0f, std::abs(v), n);
          }
        }
      }
    }
  });
  for (auto& band : found) out.insert(out.end(), band.begin(), band.end());
  return out;
}

}  // namespace corridor::localizer
