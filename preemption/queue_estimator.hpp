// Detector counts per approach of one intersection: cumulative arrivals A(t) and departures D(t),
// the arrival rate that projects A forward, and the queue (A − D) now.
#pragma once

#include <array>
#include <stdexcept>
#include <vector>

#include "maps/signal_plan.hpp"

namespace corridor::preemption {

class CountError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

class QueueEstimator {
 public:
  // Counts observed in (previous report, time_s]. Throws CountError for negative or non-finite
  // counts and for a time earlier than the last report of that approach.
  void record(maps::Compass approach, double time_s, double arrivals, double departures);

  [[nodiscard]] bool has_data(maps::Compass approach) const;
  // A(t), projected with the recent arrival rate beyond the last report.
  [[nodiscard]] double arrivals_at(maps::Compass approach, double t_s) const;
  // D(t), interpolated between reports (held constant after the last).
  [[nodiscard]] double departures_at(maps::Compass approach, double t_s) const;
  [[nodiscard]] double queue_now(maps::Compass approach) const;
  [[nodiscard]] double arrival_rate_vps(maps::Compass approach) const;

 private:
  struct Sample {
    double time_s;
    double cumulative_arrivals;
    double cumulative_departures;
  };
  struct Series {
    std::vector<Sample> samples;
    double rate_vps = 0.0;  // exponentially smoothed arrivals per second
  };
  std::array<Series, 4> series_;
};

}  // namespace corridor::preemption
