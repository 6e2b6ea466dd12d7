// ClosedLoopResult as JSON: what `corridor sim` prints and how `experiment sumo` passes a run's
// result from its child process back to the parent.
#pragma once

#include <nlohmann/json.hpp>

#include "sim/closed_loop.hpp"

namespace corridor::sim {

NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(EvTrip, from, to, depart_s, priority)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(EvOutcome, id, trip, arrived, travel_time_s, stops, wait_s, time_loss_s,
                                                deferrals, preempted_signals)
// With defaults: a record written before a key existed still reads.
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(ClosedLoopResult, ev_arrived, ev_travel_time_s, ev_stops, ev_wait_s,
                                                ev_time_loss_s, preempted_signals, preemptions_started,
                                                preemptions_released, lights_taken_over, lights_back_on_program,
                                                safety_violations, collisions, teleports, replans, route_changes,
                                                congestion_updates, others_mean_time_loss_s, others, end_time_s, evs,
                                                deferrals, approaches_with_detectors)

}  // namespace corridor::sim
