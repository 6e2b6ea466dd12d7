#include "sim/time_space.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <fstream>

#include "planner/experiments/svg_chart.hpp"
#include "sim/errors.hpp"

namespace corridor::sim {
namespace {

constexpr double kWidth = 760.0, kHeight = 480.0, kLeft = 70.0, kRight = 150.0, kTop = 40.0, kBottom = 56.0;
constexpr const char* kTrackColours[] = {"#000000", "#1f77b4", "#9467bd", "#8c564b"};

const char* light_colour(char state) {
  if (state == 'G') return "#2ca02c";
  if (state == 'y') return "#f2c500";
  return "#d62728";
}

void write_file(const std::filesystem::path& file, const std::string& text) {
  std::ofstream out(file, std::ios::trunc);
  out << text;
  if (!out) throw SimError("cannot write " + file.string());
}

}  // namespace

std::string render_time_space_svg(const std::vector<TimeSpaceTrack>& tracks, const std::string& title) {
  double t_lo = 1e300, t_hi = -1e300, d_hi = 1.0;
  for (const auto& tr : tracks) {
    for (double t : tr.t_s) t_lo = std::min(t_lo, t), t_hi = std::max(t_hi, t);
    for (double d : tr.distance_m) d_hi = std::max(d_hi, d);
  }
  if (t_lo >= t_hi) t_lo = 0.0, t_hi = 1.0;
  const auto tx = planner::nice_ticks(t_lo, t_hi);
  const auto ty = planner::nice_ticks(0.0, d_hi);
  t_lo = std::min(t_lo, tx.front());
  t_hi = std::max(t_hi, tx.back());
  d_hi = std::max(d_hi, ty.back());
  const auto px = [&](double t) { return kLeft + (t - t_lo) / (t_hi - t_lo) * (kWidth - kLeft - kRight); };
  const auto py = [&](double d) { return kHeight - kBottom - d / d_hi * (kHeight - kTop - kBottom); };

  std::string s = fmt::format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{0:.0f}\" height=\"{1:.0f}\" viewBox=\"0 0 {0:.0f} {1:.0f}\" "
      "font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n",
      kWidth, kHeight);
  std::string safe_title;
  for (char c : title) safe_title += (c == '<' || c == '>' || c == '&' || c == '"') ? ' ' : c;
  s += fmt::format("<text x=\"{:.1f}\" y=\"22\" text-anchor=\"middle\" font-size=\"15\">{}</text>\n",
                   (kLeft + kWidth - kRight) / 2, safe_title);
  s += fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\" text-anchor=\"middle\">simulation time (s)</text>\n",
                   (kLeft + kWidth - kRight) / 2, kHeight - 14);
  s += fmt::format("<text transform=\"translate(18 {:.1f}) rotate(-90)\" text-anchor=\"middle\">distance along the EV's path (m)</text>\n",
                   (kTop + kHeight - kBottom) / 2);
  for (double t : tx) {
    s += fmt::format("<line x1=\"{0:.1f}\" y1=\"{1:.1f}\" x2=\"{0:.1f}\" y2=\"{2:.1f}\" stroke=\"#ddd\"/>\n", px(t), kTop, kHeight - kBottom);
    s += fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\" text-anchor=\"middle\">{:.0f}</text>\n", px(t), kHeight - kBottom + 16, t);
  }
  for (double d : ty) {
    s += fmt::format("<line x1=\"{0:.1f}\" y1=\"{2:.1f}\" x2=\"{1:.1f}\" y2=\"{2:.1f}\" stroke=\"#ddd\"/>\n", kLeft, kWidth - kRight, py(d));
    s += fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\" text-anchor=\"end\">{:.0f}</text>\n", kLeft - 6, py(d) + 4, d);
  }
  // Signals: a bar per light interval at the stop line's distance, for the first EV's path only
  // (other EVs' distances run along other paths; their lights are in the CSV).
  for (std::size_t k = 0; k < tracks.size() && k < 1; ++k) {
    for (const auto& sig : tracks[k].signals) {
      for (std::size_t i = 0; i + 1 < sig.states.size(); ++i) {
        const double a = std::max(sig.states[i].first, t_lo), b = std::min(sig.states[i + 1].first, t_hi);
        if (b <= a) continue;
        s += fmt::format("<line x1=\"{:.2f}\" y1=\"{:.2f}\" x2=\"{:.2f}\" y2=\"{:.2f}\" stroke=\"{}\" stroke-width=\"5\"/>\n",
                         px(a), py(sig.distance_m), px(b), py(sig.distance_m), light_colour(sig.states[i].second));
      }
      s += fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\" font-size=\"10\">{}{}</text>\n", kWidth - kRight + 6,
                       py(sig.distance_m) + 3, sig.tls.substr(0, 18), sig.preempted ? " (held)" : "");
    }
  }
  for (std::size_t k = 0; k < tracks.size(); ++k) {
    const auto& tr = tracks[k];
    std::string points;
    for (std::size_t i = 0; i < tr.t_s.size(); ++i) points += fmt::format("{:.1f},{:.1f} ", px(tr.t_s[i]), py(tr.distance_m[i]));
    s += fmt::format("<polyline fill=\"none\" stroke=\"{}\" stroke-width=\"1.8\" points=\"{}\"/>\n",
                     kTrackColours[k % std::size(kTrackColours)], points);
  }
  s += fmt::format("<rect x=\"{:.1f}\" y=\"{:.1f}\" width=\"{:.1f}\" height=\"{:.1f}\" fill=\"none\" stroke=\"#444\"/>\n",
                   kLeft, kTop, kWidth - kLeft - kRight, kHeight - kTop - kBottom);
  s += "</svg>\n";
  return s;
}

void write_time_space(const std::filesystem::path& stem, const std::vector<TimeSpaceTrack>& tracks, const std::string& title) {
  std::string trajectory = "ev,t_s,distance_m,speed_mps\n";
  std::string signals = "ev,tls,distance_m,preempted,t_s,state\n";
  for (const auto& tr : tracks) {
    for (std::size_t i = 0; i < tr.t_s.size(); ++i) {
      trajectory += fmt::format("{},{:.2f},{:.2f},{:.2f}\n", tr.ev, tr.t_s[i], tr.distance_m[i], tr.speed_mps[i]);
    }
    for (const auto& sig : tr.signals) {
      for (const auto& [t, state] : sig.states) {
        signals += fmt::format("{},{},{:.2f},{},{:.2f},{}\n", tr.ev, sig.tls, sig.distance_m, sig.preempted ? 1 : 0, t, state);
      }
    }
  }
  write_file(stem.string() + ".ev_trajectory.csv", trajectory);
  write_file(stem.string() + ".ev_signals.csv", signals);
  write_file(stem.string() + ".time_space.svg", render_time_space_svg(tracks, title));
}

}  // namespace corridor::sim
