// ClosedLoopResult as JSON: what `corridor sim` prints and how `experiment sumo` passes a run's
// result from its child process back to the parent.
#pragma once

#include <nlohmann/json.hpp>

#include "sim/closed_loop.hpp"

namespace corridor::sim {

NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(EvTrip, from, to, depart_s, priority)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(EvOutcome, id, trip, arrived, travel_time_s, stops, wait_s, time_loss_s,
                                                deferrals, preempted_signals)
// One character of a light's state, as a one-letter string.
inline void to_json(nlohmann::json& j, const CollisionRecord& c) {
  j = {{"time_s", c.time_s}, {"collider", c.collider}, {"victim", c.victim}, {"collider_type", c.collider_type},
       {"victim_type", c.victim_type}, {"kind", c.kind}, {"lane", c.lane}, {"tls", c.tls},
       {"collider_light", std::string(1, c.collider_light)}, {"victim_light", std::string(1, c.victim_light)},
       {"held_by_corridor", c.held_by_corridor}, {"ev_involved", c.ev_involved}, {"collider_lane", c.collider_lane},
       {"victim_lane", c.victim_lane}, {"collider_link", c.collider_link}, {"victim_link", c.victim_link},
       {"links_conflict", c.links_conflict}};
}
inline void from_json(const nlohmann::json& j, CollisionRecord& c) {
  c.time_s = j.value("time_s", 0.0);
  c.collider = j.value("collider", std::string{});
  c.victim = j.value("victim", std::string{});
  c.collider_type = j.value("collider_type", std::string{});
  c.victim_type = j.value("victim_type", std::string{});
  c.kind = j.value("kind", std::string{});
  c.lane = j.value("lane", std::string{});
  c.tls = j.value("tls", std::string{});
  const auto light = [&](const char* key) {
    const std::string s = j.value(key, std::string("-"));
    return s.empty() ? '-' : s.front();
  };
  c.collider_light = light("collider_light");
  c.victim_light = light("victim_light");
  c.held_by_corridor = j.value("held_by_corridor", false);
  c.ev_involved = j.value("ev_involved", false);
  c.collider_lane = j.value("collider_lane", std::string{});
  c.victim_lane = j.value("victim_lane", std::string{});
  c.collider_link = j.value("collider_link", -1);
  c.victim_link = j.value("victim_link", -1);
  c.links_conflict = j.value("links_conflict", false);
}

// With defaults: a record written before a key existed still reads.
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(ClosedLoopResult, ev_arrived, ev_travel_time_s, ev_stops, ev_wait_s,
                                                ev_time_loss_s, preempted_signals, preemptions_started,
                                                preemptions_released, lights_taken_over, lights_back_on_program,
                                                safety_violations, collisions, teleports, replans, route_changes,
                                                congestion_updates, others_mean_time_loss_s, others, end_time_s, evs,
                                                deferrals, approaches_with_detectors, approaches_with_loops,
                                                collision_records)

}  // namespace corridor::sim
