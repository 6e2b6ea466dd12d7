#include "preemption/queue_estimator.hpp"

#include <algorithm>
#include <cmath>
#include <string>

namespace corridor::preemption {
namespace {
constexpr double kRateSmoothing = 0.3;  // weight of the newest interval in the arrival rate
constexpr std::size_t kMaxSamples = 512;
}  // namespace

void QueueEstimator::record(maps::Compass approach, double time_s, double arrivals, double departures) {
  if (!std::isfinite(time_s) || !std::isfinite(arrivals) || !std::isfinite(departures) || arrivals < 0 || departures < 0) {
    throw CountError("detector counts must be finite and >= 0, at a finite time");
  }
  Series& s = series_[static_cast<int>(approach)];
  if (!s.samples.empty() && time_s < s.samples.back().time_s) {
    throw CountError("detector counts for approach " + std::string{maps::compass_letter(approach)} +
                     " go back in time (" + std::to_string(time_s) + " s after " +
                     std::to_string(s.samples.back().time_s) + " s)");
  }
  const Sample last = s.samples.empty() ? Sample{time_s, 0.0, 0.0} : s.samples.back();
  if (!s.samples.empty() && time_s > last.time_s) {
    const double rate = arrivals / (time_s - last.time_s);
    s.rate_vps = s.samples.size() == 1 ? rate : (1 - kRateSmoothing) * s.rate_vps + kRateSmoothing * rate;
  }
  s.samples.push_back({time_s, last.cumulative_arrivals + arrivals, last.cumulative_departures + departures});
  if (s.samples.size() > kMaxSamples) s.samples.erase(s.samples.begin(), s.samples.begin() + kMaxSamples / 2);
}

bool QueueEstimator::has_data(maps::Compass approach) const { return !series_[static_cast<int>(approach)].samples.empty(); }

double QueueEstimator::arrival_rate_vps(maps::Compass approach) const { return series_[static_cast<int>(approach)].rate_vps; }

double QueueEstimator::arrivals_at(maps::Compass approach, double t_s) const {
  const Series& s = series_[static_cast<int>(approach)];
  if (s.samples.empty()) return 0.0;
  const Sample& last = s.samples.back();
  if (t_s >= last.time_s) return last.cumulative_arrivals + s.rate_vps * (t_s - last.time_s);
  auto it = std::lower_bound(s.samples.begin(), s.samples.end(), t_s, [](const Sample& a, double t) { return a.time_s < t; });
  return it->cumulative_arrivals;
}

double QueueEstimator::departures_at(maps::Compass approach, double t_s) const {
  const Series& s = series_[static_cast<int>(approach)];
  if (s.samples.empty()) return 0.0;
  if (t_s >= s.samples.back().time_s) return s.samples.back().cumulative_departures;
  if (t_s <= s.samples.front().time_s) return s.samples.front().cumulative_departures;
  auto hi = std::lower_bound(s.samples.begin(), s.samples.end(), t_s, [](const Sample& a, double t) { return a.time_s < t; });
  auto lo = hi - 1;
  const double f = (t_s - lo->time_s) / (hi->time_s - lo->time_s);
  return lo->cumulative_departures + f * (hi->cumulative_departures - lo->cumulative_departures);
}

double QueueEstimator::queue_now(maps::Compass approach) const {
  const Series& s = series_[static_cast<int>(approach)];
  return s.samples.empty() ? 0.0 : std::max(0.0, s.samples.back().cumulative_arrivals - s.samples.back().cumulative_departures);
}

}  // namespace corridor::preemption
