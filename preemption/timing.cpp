#include "preemption/timing.hpp"

#include <algorithm>

namespace corridor::preemption {

double transition_time_s(double remaining_min_green_s, double yellow_s, double all_red_s) {
  return std::max(0.0, remaining_min_green_s) + yellow_s + all_red_s;
}

double queue_at_arrival_veh(double tau_s, const QueueInputs& q, const TimingConfig& c) {
  const double n = q.green_on
                       ? q.arrivals_at_tau - q.departures_at_green_start - c.saturation_flow_vps * (tau_s - q.green_start_s)
                       : q.arrivals_at_tau - q.departures_at_green_end;
  return std::max(0.0, n);
}

double queue_clearance_s(double queued_veh, const TimingConfig& c) {
  return c.startup_lost_time_s + c.saturation_headway_s * queued_veh;
}

double preemption_start_s(double tau_s, double trans_s, double clearance_s, const TimingConfig& c) {
  return tau_s - trans_s - c.safety_margin_s - clearance_s;
}

}  // namespace corridor::preemption
