// When to start a preemption: the seed paper's equations for the start time p, the transition time
// Trans and the queue clearance time t_q, from the predicted arrival τ and detector counts.
#pragma once

namespace corridor::preemption {

struct TimingConfig {
  double safety_margin_s = 3.0;
  double startup_lost_time_s = 2.0;   // l1
  double saturation_headway_s = 2.0;  // h, seconds per queued vehicle
  double saturation_flow_vps = 0.5;   // s, vehicles per second of green
};

// Trans: the time to end the current phase safely.
double transition_time_s(double remaining_min_green_s, double yellow_s, double all_red_s);

// What the detectors say about the vehicle's approach (cumulative counts since any fixed origin).
struct QueueInputs {
  double arrivals_at_tau = 0.0;           // A(τ): cumulative arrivals predicted at the vehicle's arrival
  double departures_at_green_start = 0.0;  // D(t_G0)
  double departures_at_green_end = 0.0;    // D(t_G0 + g), for an approach that is red
  double green_start_s = 0.0;              // t_G0
  bool green_on = false;                   // the approach has green now
};

// n_q(τ) = max{0, A(τ) − D(t_G0) − s·(τ − t_G0)} while green is on, else max{0, A(τ) − D(t_G0 + g)}.
double queue_at_arrival_veh(double tau_s, const QueueInputs& q, const TimingConfig& c);

// t_q(τ) = l1 + h · n_q(τ).
double queue_clearance_s(double queued_veh, const TimingConfig& c);

// p = τ − Trans − safety_margin (uncongested), and p = τ − Trans − safety_margin − t_q(τ) (congested).
double preemption_start_s(double tau_s, double trans_s, double queue_clearance_s, const TimingConfig& c);

}  // namespace corridor::preemption
