// Drives one emergency-vehicle trip through a list of unforeseen congestion events, with static or
// dynamic (D* Lite) routing and with or without perfect preemption: the seed paper's analytical
// model (section IV.A). Travel time is what the vehicle experiences, not what a planner predicted.
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "planner/dstar_lite.hpp"
#include "planner/travel_cost.hpp"

namespace corridor::planner {

// From `time_s` after departure on, the vehicle waits `queue_delay_s` when it takes `edge`. Both
// strategies learn of it at that moment; a later event on the same edge replaces it.
struct CongestionEvent {
  double time_s = 0.0;
  EdgeId edge;
  double queue_delay_s = 0.0;
};

struct TripScenario {
  NodeId source;
  NodeId destination;
  std::vector<double> signal_delay_s;   // per node: the wait at its signal without preemption
  std::vector<CongestionEvent> events;  // any order
};

enum class Routing { static_route, dynamic_route };
enum class Signals { no_preemption, preemption };
const char* to_string(Routing r);
const char* to_string(Signals s);

struct TripResult {
  double travel_time_s = 0.0;
  double signal_wait_s = 0.0;  // part of the travel time spent at red signals
  double queue_wait_s = 0.0;   // part spent in congestion queues
  std::vector<EdgeId> driven;
  std::vector<EdgeId> planned_at_departure;
  std::uint32_t replans = 0;        // replans with new congestion to take in
  std::uint32_t route_changes = 0;  // of those, how many changed the route ahead
  std::uint64_t expanded = 0;       // D* Lite vertex expansions after departure
  double replan_wall_s = 0.0;       // wall time of those replans (not deterministic)

  [[nodiscard]] bool rerouted() const { return driven != planned_at_departure; }
};

// Called after every replan of the dynamic strategy, with the planner and the costs it knows.
using ReplanObserver = std::function<void(const DStarLite& planner, const TravelCost& known)>;

// A trip from node v starts at offset 0 of any of its out-edges, and one to v ends at the end of
// any of its in-edges.
std::vector<EdgePoint> node_departures(const maps::RoadGraph& graph, NodeId v);
std::vector<EdgePoint> node_arrivals(const maps::RoadGraph& graph, NodeId v);

// The delay in force on `edge` at `time_s` under `events` sorted by time.
double queue_delay_at(std::span<const CongestionEvent> sorted_events, EdgeId edge, double time_s);

// The model: the vehicle decides, and the queue of the edge it takes is fixed, when it reaches the
// stop line of the edge's tail, knowing every event up to that moment. Without preemption it then
// waits that intersection's signal delay (not at the source; the destination is never crossed).
// Perfect preemption removes every signal wait; it does not clear congestion queues.
// Throws std::invalid_argument for a bad scenario or when the destination is unreachable.
TripResult drive_trip(const maps::RoadGraph& graph, const TripScenario& scenario, Routing routing, Signals signals,
                      VehicleProfile vehicle, const ReplanObserver& observer = {});

// The pair's base travel time: no congestion, no signal delay.
double base_travel_time_s(const maps::RoadGraph& graph, NodeId source, NodeId destination, VehicleProfile vehicle);

// The static plan for a scenario before departure (no events known), with its predicted arrival
// time at every node: where experiments place congestion, and when it may appear.
Route static_plan(const maps::RoadGraph& graph, const TripScenario& scenario, Signals signals, VehicleProfile vehicle);

}  // namespace corridor::planner
