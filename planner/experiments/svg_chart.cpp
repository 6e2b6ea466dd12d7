#include "planner/experiments/svg_chart.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace corridor::planner {
namespace {

constexpr double kWidth = 720.0;
constexpr double kHeight = 440.0;
constexpr double kLeft = 72.0;
constexpr double kRight = 205.0;  // room for the legend
constexpr double kTop = 40.0;
constexpr double kBottom = 56.0;
// Distinguishable in colour and in grey print: colour plus dash pattern plus marker.
constexpr const char* kColours[] = {"#d62728", "#ff7f0e", "#1f77b4", "#2ca02c", "#9467bd", "#8c564b"};
constexpr const char* kDashes[] = {"6 4", "2 3", "", "10 3 2 3", "4 2", "1 2"};

std::string escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '&': out += "&amp;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string tick_label(double v, double step) {
  const int decimals = step >= 1.0 ? 0 : static_cast<int>(std::ceil(-std::log10(step) - 1e-9));
  return fmt::format("{:.{}f}", std::abs(v) < step * 1e-9 ? 0.0 : v, std::clamp(decimals, 0, 6));
}

struct Frame {
  double x_lo, x_hi, y_lo, y_hi;
  [[nodiscard]] double px(double x) const { return kLeft + (x - x_lo) / (x_hi - x_lo) * (kWidth - kLeft - kRight); }
  [[nodiscard]] double py(double y) const { return kHeight - kBottom - (y - y_lo) / (y_hi - y_lo) * (kHeight - kTop - kBottom); }
};

std::string header(const ChartText& text) {
  std::string s = fmt::format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{:.0f}\" height=\"{:.0f}\" viewBox=\"0 0 {:.0f} {:.0f}\" "
      "font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n",
      kWidth, kHeight, kWidth, kHeight);
  s += fmt::format("<text x=\"{:.1f}\" y=\"22\" text-anchor=\"middle\" font-size=\"15\">{}</text>\n",
                   (kLeft + kWidth - kRight) / 2, escape(text.title));
  s += fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\" text-anchor=\"middle\">{}</text>\n", (kLeft + kWidth - kRight) / 2,
                   kHeight - 14, escape(text.x_label));
  s += fmt::format("<text transform=\"translate(18 {:.1f}) rotate(-90)\" text-anchor=\"middle\">{}</text>\n",
                   (kTop + kHeight - kBottom) / 2, escape(text.y_label));
  return s;
}

std::string y_axis(const Frame& f, const std::vector<double>& ticks) {
  std::string s;
  const double step = ticks.size() > 1 ? ticks[1] - ticks[0] : 1.0;
  for (double t : ticks) {
    s += fmt::format("<line x1=\"{:.1f}\" x2=\"{:.1f}\" y1=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"#ddd\"/>\n", kLeft,
                     kWidth - kRight, f.py(t), f.py(t));
    s += fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\" text-anchor=\"end\">{}</text>\n", kLeft - 6, f.py(t) + 4,
                     tick_label(t, step));
  }
  s += fmt::format("<rect x=\"{:.1f}\" y=\"{:.1f}\" width=\"{:.1f}\" height=\"{:.1f}\" fill=\"none\" stroke=\"#333\"/>\n",
                   kLeft, kTop, kWidth - kLeft - kRight, kHeight - kTop - kBottom);
  return s;
}

std::string legend(const std::vector<ChartSeries>& series, bool bars) {
  std::string s;
  for (std::size_t i = 0; i < series.size(); ++i) {
    const double y = kTop + 14 + 20.0 * static_cast<double>(i);
    const double x = kWidth - kRight + 14;
    const char* colour = kColours[i % std::size(kColours)];
    if (bars) {
      s += fmt::format("<rect x=\"{:.1f}\" y=\"{:.1f}\" width=\"22\" height=\"10\" fill=\"{}\"/>\n", x, y - 8, colour);
    } else {
      s += fmt::format("<line x1=\"{:.1f}\" x2=\"{:.1f}\" y1=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"{}\" stroke-width=\"2\" "
                       "stroke-dasharray=\"{}\"/>\n",
                       x, x + 22, y - 3, y - 3, colour, kDashes[i % std::size(kDashes)]);
    }
    s += fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\">{}</text>\n", x + 28, y + 1, escape(series[i].label));
  }
  return s;
}

std::pair<double, double> padded(double lo, double hi) {
  if (lo == hi) return {lo - 1.0, hi + 1.0};
  return {lo, hi};
}

}  // namespace

std::vector<double> nice_ticks(double lo, double hi, int target_count) {
  if (!(std::isfinite(lo) && std::isfinite(hi)) || hi < lo || target_count < 2) {
    throw std::invalid_argument("nice_ticks needs a finite range and at least two ticks");
  }
  if (hi == lo) hi = lo + 1.0;
  const double raw = (hi - lo) / (target_count - 1);
  const double power = std::pow(10.0, std::floor(std::log10(raw)));
  double step = 10.0 * power;
  for (double m : {1.0, 2.0, 2.5, 5.0}) {
    if (m * power >= raw * (1.0 - 1e-12)) {
      step = m * power;
      break;
    }
  }
  std::vector<double> ticks;
  const double first = std::floor(lo / step + 1e-9) * step;
  for (double t = first; t <= hi + step * (1.0 - 1e-9); t += step) ticks.push_back(std::round(t / step) * step);
  return ticks;
}

std::string render_line_chart(const ChartText& text, const std::vector<ChartSeries>& series, bool y_from_zero) {
  double x_lo = std::numeric_limits<double>::infinity(), x_hi = -x_lo, y_lo = x_lo, y_hi = -x_lo;
  for (const ChartSeries& s : series) {
    if (s.x.size() != s.y.size()) throw std::invalid_argument("chart series '" + s.label + "': x and y differ in length");
    for (std::size_t i = 0; i < s.x.size(); ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) continue;
      x_lo = std::min(x_lo, s.x[i]);
      x_hi = std::max(x_hi, s.x[i]);
      y_lo = std::min(y_lo, s.y[i]);
      y_hi = std::max(y_hi, s.y[i]);
    }
  }
  if (!std::isfinite(x_lo)) throw std::invalid_argument("chart '" + text.title + "' has no finite point");
  if (y_from_zero) y_lo = std::min(y_lo, 0.0);
  std::tie(x_lo, x_hi) = padded(x_lo, x_hi);
  std::tie(y_lo, y_hi) = padded(y_lo, y_hi);
  const auto xt = nice_ticks(x_lo, x_hi);
  const auto yt = nice_ticks(y_lo, y_hi);
  const Frame f{xt.front(), xt.back(), yt.front(), yt.back()};

  std::string s = header(text) + y_axis(f, yt);
  const double xstep = xt.size() > 1 ? xt[1] - xt[0] : 1.0;
  for (double t : xt) {
    s += fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\" text-anchor=\"middle\">{}</text>\n", f.px(t),
                     kHeight - kBottom + 16, tick_label(t, xstep));
  }
  for (std::size_t i = 0; i < series.size(); ++i) {
    const char* colour = kColours[i % std::size(kColours)];
    std::string points;
    std::string markers;
    for (std::size_t k = 0; k < series[i].x.size(); ++k) {
      if (!std::isfinite(series[i].x[k]) || !std::isfinite(series[i].y[k])) continue;
      const double px = f.px(series[i].x[k]);
      const double py = f.py(series[i].y[k]);
      points += fmt::format("{:.1f},{:.1f} ", px, py);
      if (series[i].x.size() <= 40) {
        markers += fmt::format("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"2.5\" fill=\"{}\"/>\n", px, py, colour);
      }
    }
    s += fmt::format("<polyline fill=\"none\" stroke=\"{}\" stroke-width=\"2\" stroke-dasharray=\"{}\" points=\"{}\"/>\n",
                     colour, kDashes[i % std::size(kDashes)], points);
    s += markers;
  }
  return s + legend(series, false) + "</svg>\n";
}

std::string render_bar_chart(const ChartText& text, const std::vector<std::string>& categories,
                             const std::vector<ChartSeries>& series) {
  if (categories.empty() || series.empty()) throw std::invalid_argument("bar chart '" + text.title + "' has no data");
  double y_lo = 0.0, y_hi = 0.0;
  for (const ChartSeries& s : series) {
    if (s.y.size() != categories.size()) {
      throw std::invalid_argument("bar series '" + s.label + "' needs one value per category");
    }
    for (double v : s.y) {
      if (!std::isfinite(v)) continue;
      y_lo = std::min(y_lo, v);
      y_hi = std::max(y_hi, v);
    }
  }
  std::tie(y_lo, y_hi) = padded(y_lo, y_hi);
  const auto yt = nice_ticks(y_lo, y_hi);
  const Frame f{0.0, static_cast<double>(categories.size()), yt.front(), yt.back()};
  std::string s = header(text) + y_axis(f, yt);
  const double group = f.px(1.0) - f.px(0.0);
  const double bar = group * 0.8 / static_cast<double>(series.size());
  for (std::size_t k = 0; k < categories.size(); ++k) {
    s += fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\" text-anchor=\"middle\">{}</text>\n", f.px(k + 0.5),
                     kHeight - kBottom + 16, escape(categories[k]));
    for (std::size_t i = 0; i < series.size(); ++i) {
      const double v = series[i].y[k];
      if (!std::isfinite(v)) continue;
      const double x = f.px(static_cast<double>(k)) + group * 0.1 + bar * static_cast<double>(i);
      const double top = f.py(std::max(v, 0.0));
      const double height = std::abs(f.py(v) - f.py(0.0));
      s += fmt::format("<rect x=\"{:.1f}\" y=\"{:.1f}\" width=\"{:.1f}\" height=\"{:.1f}\" fill=\"{}\"><title>{}: {:.1f}</title></rect>\n",
                       x, top, bar * 0.92, height, kColours[i % std::size(kColours)], escape(series[i].label), v);
    }
  }
  return s + legend(series, true) + "</svg>\n";
}

}  // namespace corridor::planner
