// ClosedLoopResult as JSON: what `corridor sim` prints and how `experiment sumo` passes a run's
// result from its child process back to the parent.
#pragma once

#include <nlohmann/json.hpp>

#include "sim/closed_loop.hpp"

namespace corridor::sim {

NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(ClosedLoopResult, ev_arrived, ev_travel_time_s, ev_stops, ev_wait_s, ev_time_loss_s,
                                   preempted_signals, preemptions_started, preemptions_released, lights_taken_over,
                                   lights_back_on_program, safety_violations, collisions, teleports, replans,
                                   route_changes, congestion_updates, others_mean_time_loss_s, others, end_time_s)

}  // namespace corridor::sim
