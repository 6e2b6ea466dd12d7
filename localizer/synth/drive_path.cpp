#include "localizer/synth/drive_path.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace corridor::localizer::synth {
namespace {

std::vector<maps::Point2> resample(const std::vector<maps::Point2>& line, double spacing) {
  std::vector<maps::Point2> out;
  if (line.empty()) return out;
  out.push_back(line.front());
  double carry = 0.0;  // distance already walked since the last emitted sample
  for (std::size_t i = 1; i < line.size(); ++i) {
    const maps::Point2 a = line[i - 1];
    const maps::Point2 b = line[i];
    const double len = maps::distance_m(a, b);
    double s = spacing - carry;
    while (s <= len) {
      const double f = s / len;
      out.push_back({a.x_m + f * (b.x_m - a.x_m), a.y_m + f * (b.y_m - a.y_m)});
      s += spacing;
    }
    carry = len - (s - spacing);
  }
  return out;
}

double wrap_angle(double a) {
  while (a > std::numbers::pi) a -= 2 * std::numbers::pi;
  while (a < -std::numbers::pi) a += 2 * std::numbers::pi;
  return a;
}

}  // namespace

std::vector<maps::Point2> smooth_polyline(const std::vector<maps::Point2>& polyline, double sigma_m, double spacing_m) {
  const auto pts = resample(polyline, spacing_m);
  if (sigma_m <= 0 || pts.size() < 3) return pts;
  const int radius = static_cast<int>(std::ceil(3 * sigma_m / spacing_m));
  const double sigma = sigma_m / spacing_m;
  std::vector<double> w(2 * radius + 1);
  for (int k = -radius; k <= radius; ++k) w[k + radius] = std::exp(-0.5 * k * k / (sigma * sigma));
  const int n = static_cast<int>(pts.size());
  std::vector<maps::Point2> out(pts.size());
  for (int i = 0; i < n; ++i) {
    // Near the ends the window shrinks symmetrically, so the endpoints stay where they are.
    const int r = std::min({radius, i, n - 1 - i});
    double sx = 0, sy = 0, sw = 0;
    for (int k = -r; k <= r; ++k) {
      sx += w[k + radius] * pts[i + k].x_m;
      sy += w[k + radius] * pts[i + k].y_m;
      sw += w[k + radius];
    }
    out[i] = {sx / sw, sy / sw};
  }
  return out;
}

double total_turn_deg(const std::vector<maps::Point2>& polyline, double corner_smoothing_m, double length_m) {
  constexpr double kStep = 2.0;
  const auto pts = smooth_polyline(polyline, corner_smoothing_m, kStep);
  const std::size_t n = std::min(pts.size(), static_cast<std::size_t>(length_m / kStep) + 1);
  double sum = 0;
  for (std::size_t i = 2; i < n; ++i) {
    const double a = std::atan2(pts[i - 1].y_m - pts[i - 2].y_m, pts[i - 1].x_m - pts[i - 2].x_m);
    const double b = std::atan2(pts[i].y_m - pts[i - 1].y_m, pts[i].x_m - pts[i - 1].x_m);
    sum += std::abs(wrap_angle(b - a));
  }
  return sum * 180.0 / std::numbers::pi;
}

std::vector<DriveSample> plan_drive(const std::vector<maps::Point2>& polyline, const DriveOptions& o) {
  constexpr double kSpacing = 0.5;
  const auto pts = smooth_polyline(polyline, o.corner_smoothing_m, kSpacing);
  if (pts.size() < 40) throw std::invalid_argument("the drive needs a polyline of at least 20 m");
  const std::size_t n = pts.size();
  std::vector<double> arc(n, 0.0), heading(n), speed(n);
  for (std::size_t i = 1; i < n; ++i) arc[i] = arc[i - 1] + maps::distance_m(pts[i - 1], pts[i]);
  for (std::size_t i = 0; i < n; ++i) {
    const auto& a = pts[i == 0 ? 0 : i - 1];
    const auto& b = pts[i + 1 == n ? n - 1 : i + 1];
    heading[i] = std::atan2(b.y_m - a.y_m, b.x_m - a.x_m);
  }
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t a = i == 0 ? 0 : i - 1;
    const std::size_t b = i + 1 == n ? n - 1 : i + 1;
    const double kappa = std::abs(wrap_angle(heading[b] - heading[a])) / std::max(arc[b] - arc[a], 1e-6);
    speed[i] = std::min(o.cruise_speed_mps, std::sqrt(o.max_lateral_accel_mps2 / std::max(kappa, 1e-9)));
  }
  // Longitudinal limit: v² may change by at most 2·a·ds between samples, both ways.
  for (std::size_t i = 1; i < n; ++i) {
    speed[i] = std::min(speed[i], std::sqrt(speed[i - 1] * speed[i - 1] + 2 * o.max_long_accel_mps2 * kSpacing));
  }
  for (std::size_t i = n - 1; i-- > 0;) {
    speed[i] = std::min(speed[i], std::sqrt(speed[i + 1] * speed[i + 1] + 2 * o.max_long_accel_mps2 * kSpacing));
  }
  std::vector<double> time(n, 0.0);
  for (std::size_t i = 1; i < n; ++i) time[i] = time[i - 1] + (arc[i] - arc[i - 1]) * 2 / (speed[i] + speed[i - 1]);

  const double end_arc = o.max_length_m > 0 ? std::min(o.max_length_m, arc.back()) : arc.back();
  std::vector<DriveSample> out;
  std::size_t j = 0;
  for (int k = 0;; ++k) {
    const double t = k / o.frame_rate_hz;
    while (j + 1 < n && time[j + 1] < t) ++j;
    if (j + 1 >= n) break;
    const double f = (t - time[j]) / (time[j + 1] - time[j]);
    const double s = arc[j] + f * (arc[j + 1] - arc[j]);
    if (s > end_arc) break;
    DriveSample d;
    d.time_s = t;
    d.arc_m = s;
    d.position = {pts[j].x_m + f * (pts[j + 1].x_m - pts[j].x_m), pts[j].y_m + f * (pts[j + 1].y_m - pts[j].y_m)};
    d.heading_rad = heading[j] + f * wrap_angle(heading[j + 1] - heading[j]);
    out.push_back(d);
  }
  return out;
}

}  // namespace corridor::localizer::synth
