#include "localizer/vo/zncc.hpp"

#include <algorithm>
#include <cmath>

namespace corridor::localizer {

NormalizedPatch NormalizedPatch::normalize(std::vector<float> values) {
  double mean = 0;
  for (const float v : values) mean += v;
  mean /= static_cast<double>(values.size());
  double norm = 0;
  for (float& v : values) {
    v = static_cast<float>(v - mean);
    norm += static_cast<double>(v) * v;
  }
  NormalizedPatch p;
  // A flat patch (norm of about one grey level per pixel) has no defined correlation.
  if (norm < 1.0 * static_cast<double>(values.size())) return p;
  const float inv = static_cast<float>(1.0 / std::sqrt(norm));
  for (float& v : values) v *= inv;
  p.values_ = std::move(values);
  return p;
}

NormalizedPatch NormalizedPatch::extract(const cv::Mat& img, cv::Point2f centre, int r) {
  const int x = static_cast<int>(std::lround(centre.x)), y = static_cast<int>(std::lround(centre.y));
  if (x - r < 0 || y - r < 0 || x + r >= img.cols || y + r >= img.rows) return {};
  std::vector<float> v;
  v.reserve(static_cast<std::size_t>((2 * r + 1) * (2 * r + 1)));
  for (int dy = -r; dy <= r; ++dy) {
    const auto* row = img.ptr<std::uint8_t>(y + dy);
    for (int dx = -r; dx <= r; ++dx) v.push_back(row[x + dx]);
  }
  return normalize(std::move(v));
}

NormalizedPatch NormalizedPatch::extract_subpixel(const cv::Mat& img, cv::Point2f c, int r) {
  const int x0 = static_cast<int>(std::floor(c.x)), y0 = static_cast<int>(std::floor(c.y));
  if (x0 - r < 0 || y0 - r < 0 || x0 + r + 1 >= img.cols || y0 + r + 1 >= img.rows) return {};
  const float ax = c.x - static_cast<float>(x0), ay = c.y - static_cast<float>(y0);
  std::vector<float> v;
  v.reserve(static_cast<std::size_t>((2 * r + 1) * (2 * r + 1)));
  for (int dy = -r; dy <= r; ++dy) {
    const auto* r0 = img.ptr<std::uint8_t>(y0 + dy);
    const auto* r1 = img.ptr<std::uint8_t>(y0 + dy + 1);
    for (int dx = -r; dx <= r; ++dx) {
      const int x = x0 + dx;
      v.push_back((1 - ay) * ((1 - ax) * r0[x] + ax * r0[x + 1]) + ay * ((1 - ax) * r1[x] + ax * r1[x + 1]));
    }
  }
  return normalize(std::move(v));
}

float NormalizedPatch::zncc(const NormalizedPatch& other) const {
  if (!valid() || values_.size() != other.values_.size()) return -1.0f;
  float dot = 0;
  for (std::size_t i = 0; i < values_.size(); ++i) dot += values_[i] * other.values_[i];
  return dot;
}

std::vector<Candidate> mutual_best_matches(const std::vector<Candidate>& candidates, int count_a, int count_b,
                                           float min_score) {
  std::vector<int> best_a(static_cast<std::size_t>(count_a), -1), best_b(static_cast<std::size_t>(count_b), -1);
  for (int i = 0; i < static_cast<int>(candidates.size()); ++i) {
    const Candidate& c = candidates[static_cast<std::size_t>(i)];
    if (c.score < min_score) continue;
    int& ba = best_a[static_cast<std::size_t>(c.a)];
    if (ba < 0 || candidates[static_cast<std::size_t>(ba)].score < c.score) ba = i;
    int& bb = best_b[static_cast<std::size_t>(c.b)];
    if (bb < 0 || candidates[static_cast<std::size_t>(bb)].score < c.score) bb = i;
  }
  std::vector<Candidate> out;
  for (int a = 0; a < count_a; ++a) {
    const int i = best_a[static_cast<std::size_t>(a)];
    if (i >= 0 && best_b[static_cast<std::size_t>(candidates[static_cast<std::size_t>(i)].b)] == i) {
      out.push_back(candidates[static_cast<std::size_t>(i)]);
    }
  }
  return out;
}

double parabola_peak_offset(double left, double centre, double right) {
  const double denom = left - 2 * centre + right;
  if (denom >= -1e-12) return 0.0;  // not a maximum
  return std::clamp(0.5 * (left - right) / denom, -0.5, 0.5);
}

}  // namespace corridor::localizer
