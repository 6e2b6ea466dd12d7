// One closed-loop SUMO run: background traffic, an emergency vehicle, and Corridor's planner and
// preemption engine in the loop. Every step the vehicle's position feeds D* Lite; SUMO's measured
// edge travel times feed congestion updates at a fixed period; lane halting counts feed the
// congestion classifier; route changes go back with setRoute and signal commands through the
// SUMO SignalController.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "sim/sumo_scenario.hpp"

namespace corridor::sim {

enum class EvRouting { static_route, dynamic_route };
// How Corridor talks to SUMO: TraCI over a socket to a sumo process (libtracicpp), or SUMO inside
// this process (libsumocpp): faster for batch runs, and one simulation per process.
enum class SumoBackend { traci, libsumo };
// none: an ordinary vehicle; bluelight: SUMO's bluelight device (others make way, red lights are
// passed slowly); corridor: Corridor preempts the lights ahead; corridor_bluelight: both, which is
// what a real ambulance is: a vehicle with siren privileges whose lights are also preempted.
enum class EvSignals { none, bluelight, corridor, corridor_bluelight };
const char* to_string(EvRouting r);
const char* to_string(EvSignals s);  // "none", "bluelight", "corridor", "corridor+bluelight"
// The inverses of to_string; nullopt for anything else.
std::optional<EvRouting> parse_ev_routing(const std::string& text);
std::optional<EvSignals> parse_ev_signals(const std::string& text);
[[nodiscard]] inline bool preempts(EvSignals s) { return s == EvSignals::corridor || s == EvSignals::corridor_bluelight; }
[[nodiscard]] inline bool has_bluelight(EvSignals s) { return s == EvSignals::bluelight || s == EvSignals::corridor_bluelight; }

// One emergency vehicle's trip: SUMO edges, departure (simulation time) and mission priority
// (higher is served first where two vehicles claim one signal).
struct EvTrip {
  std::string from;
  std::string to;
  double depart_s = 0.0;
  int priority = 1;
};

struct ClosedLoopConfig {
  bool with_ev = true;  // false: the baseline run for other vehicles' delay
  SumoBackend backend = SumoBackend::traci;
  // When set, the loop runs through this `corridor serve` (http://host:port), which must serve the
  // same SUMO net (--map FILE.net.xml); SUMO then keeps wall-clock pace.
  std::string server_url;
  std::string server_token;
  // With a server: the lights are NTCIP 1202 controllers, virtual agents over SUMO's own lights on
  // consecutive UDP ports from ntcip_port, which the server drives (serve --controllers with their
  // manifest), instead of the server's signal states mirrored onto SUMO: SUMO <- agent <- SNMP <- server.
  bool ntcip = false;
  std::string ntcip_host = "127.0.0.1";
  unsigned short ntcip_port = 16100;
  std::string read_community = "public";
  std::string write_community = "private";
  EvRouting routing = EvRouting::dynamic_route;
  EvSignals signals = EvSignals::corridor;
  std::string ev_from;  // SUMO edge ids
  std::string ev_to;
  double ev_depart_s = 200.0;
  double ev_vmax_kmh = 120.0;
  double congestion_period_s = 10.0;  // how often measured travel times reach the planner
  std::uint32_t incidents = 2;        // speed drops on the EV's route after it has left
  double incident_speed_mps = 2.0;
  double end_s = 1800.0;
  std::uint64_t seed = 1;
  std::filesystem::path background_routes;
  double demand_scale = 1.0;  // SUMO's --scale on all demand (a user's scenario's own)
  std::filesystem::path out_dir;  // logs and tripinfo of this run
  std::string run_name = "run";
  // With a server: what the EV's receiver reports. 0 m posts SUMO's true positions, as before;
  // otherwise fixes with this Gaussian noise at gps_rate_hz, and inside each outage (seconds after
  // the EV departs, start and end) fixes with HDOP above 10 while the EV's onboard localizer posts
  // source "vo" positions from odometry simulated from SUMO's truth with our VO's measured drift.
  double gps_noise_m = 0.0;
  double gps_rate_hz = 1.0;
  std::vector<std::pair<double, double>> gps_outages;
  // Further EVs in the same run (`--evs N`), each its own mission with its own route; the first EV
  // is ev_from/ev_to/ev_depart_s with priority first_priority.
  std::vector<EvTrip> more_evs;
  int first_priority = 1;
  // Vicinity-aware preemption: measured standing queues on the route's approaches start holds early
  // enough that the EV meets no queue, and flush a link about to spill back into the junction
  // before (preemption::VicinityConfig). Off: the seed's route-only preemption.
  bool vicinity = true;
  // The seed's Fig. 11 protocol: a flow of this many vehicles/hour along the first EV's free-flow
  // (static) route, from 10 min before it departs to the end; 0: none.
  double inject_on_route_vph = 0.0;
  // Writes <run>.ev_trajectory.csv, <run>.ev_signals.csv and <run>.time_space.svg.
  bool record_time_space = false;
};

// One EV's outcome in a run.
struct EvOutcome {
  std::string id;  // SUMO vehicle id: "ev", then "ev2", "ev3", ...
  EvTrip trip;
  bool arrived = false;
  double travel_time_s = 0.0;
  int stops = 0;
  double wait_s = 0.0;
  double time_loss_s = 0.0;
  std::size_t deferrals = 0;  // its claims that lost arbitration to a higher one
  std::size_t preempted_signals = 0;
};

// One collision SUMO reported, traced to the light it happened under: who hit whom, where, which
// link each of them was taking and what it showed them, and whether Corridor held the light.
struct CollisionRecord {
  double time_s = 0.0;
  std::string collider;
  std::string victim;
  std::string collider_type;  // vType ids ("ev_bluelight" for the EV with SUMO's device)
  std::string victim_type;
  std::string kind;  // SUMO's collision type: collision, frontal, junction, sharedLane, ...
  std::string lane;
  std::string tls;             // the light over the junction, if any
  char collider_light = '-';   // the state of the collider's link ('G', 'g', 'y', 'r'), '-' off a light
  char victim_light = '-';
  std::string collider_lane;   // where each was at the step of the collision
  std::string victim_lane;
  int collider_link = -1;      // the light's link each was taking, -1 off a light
  int victim_link = -1;
  bool links_conflict = false;  // the two links are foes under the light (false for one link, or none)
  bool held_by_corridor = false;  // the light was taken over by Corridor's controller then
  bool ev_involved = false;
};

struct ClosedLoopResult {
  bool ev_arrived = false;
  double ev_travel_time_s = 0.0;
  int ev_stops = 0;
  double ev_wait_s = 0.0;
  double ev_time_loss_s = 0.0;
  std::size_t preempted_signals = 0;  // distinct lights held for the EV
  std::size_t preemptions_started = 0;
  std::size_t preemptions_released = 0;
  std::size_t lights_taken_over = 0;
  std::size_t lights_back_on_program = 0;
  std::vector<std::string> safety_violations;
  int collisions = 0;
  int teleports = 0;
  std::uint32_t replans = 0;        // with new congestion
  std::uint32_t route_changes = 0;  // sent to SUMO with setRoute
  std::uint32_t congestion_updates = 0;
  double others_mean_time_loss_s = 0.0;
  std::size_t others = 0;
  double end_time_s = 0.0;
  std::vector<EvOutcome> evs;  // every EV, the first one first (its figures are also the fields above)
  std::size_t deferrals = 0;   // over all EVs
  std::size_t approaches_with_detectors = 0;  // approaches whose queue comes from the user's e2 detectors
  std::size_t approaches_with_loops = 0;      // approaches whose counts come from the user's induction loops
  std::vector<CollisionRecord> collision_records;  // every collision, traced
};

// Throws SimError when SUMO fails or the EV's edges are unknown or unconnected.
ClosedLoopResult run_closed_loop(const SumoScenario& scenario, const ClosedLoopConfig& config);

// `count` further EVs for a run whose first EV drives `first`: each crosses a signal of the first's
// route from another approach, departing so that both are predicted there at the same time, which
// makes their claims conflict. Priorities fall with the index (the first EV keeps the highest).
// Throws SimError when the network has no such trip.
std::vector<EvTrip> conflicting_ev_trips(const SumoScenario& scenario, const EvTrip& first, std::size_t count,
                                         std::uint64_t seed, double ev_vmax_kmh);

// A start and goal for the EV: far apart, connected, on edges SUMO lets it drive, and with at
// least two traffic lights between them where the network has two.
std::pair<std::string, std::string> pick_ev_trip(const SumoScenario& scenario, std::uint64_t seed);

}  // namespace corridor::sim
