// The closed loop's body, written once over the SUMO client API: instantiated for libtraci (a
// SUMO process over a socket) in closed_loop_traci.cpp and for libsumo (SUMO in this process) in
// closed_loop_libsumo.cpp. Both APIs share their types and constants (libsumo::TraCI*), but not
// their function namespaces, and one translation unit can include only one of them.
#pragma once

#include <libsumo/TraCIConstants.h>
#include <libsumo/TraCIDefs.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <map>
#include <optional>
#include <set>
#include <span>

#include "maps/intersection_geometry.hpp"
#include "planner/dstar_lite.hpp"
#include "planner/experiments/scenario_generator.hpp"
#include "planner/one_to_one_search.hpp"
#include "preemption/engine.hpp"
#include "preemption/signal_costs.hpp"
#include "sim/closed_loop.hpp"
#include "sim/errors.hpp"
#include "sim/sumo_bridge.hpp"
#include "sim/sumo_signal_controller.hpp"
#include "sim/time_space.hpp"
#include "sim/tripinfo.hpp"

namespace corridor::sim {

ClosedLoopResult run_closed_loop_traci(const SumoScenario& scenario, const ClosedLoopConfig& config);
ClosedLoopResult run_closed_loop_libsumo(const SumoScenario& scenario, const ClosedLoopConfig& config);
ClosedLoopResult run_closed_loop_server(const SumoScenario& scenario, const ClosedLoopConfig& config);

namespace detail {

inline constexpr const char* kEv = "ev";
inline constexpr preemption::MissionId kMission = 1;

double as_double(const libsumo::TraCIResults& r, int var);
std::string as_string(const libsumo::TraCIResults& r, int var);
// The EV's vehicle types, of SUMO class `vclass`.
void write_ev_types(const std::filesystem::path& file, double vmax_mps, const std::string& vclass);
// The vehicle type write_ev_types defines for a signal strategy.
inline const char* ev_type(EvSignals s) {
  switch (s) {
    case EvSignals::bluelight: return "ev_bluelight";
    case EvSignals::corridor_bluelight: return "ev_bluelight_preempted";
    default: return "ev";
  }
}
std::vector<std::string> sumo_ids(const maps::SumoGraph& g, std::span<const EdgeId> arcs);
// Every graph edge that puts the vehicle on `sumo_edge`, at `offset_m` (one per way onto it).
std::vector<planner::EdgePoint> points_on(const maps::SumoGraph& g, const std::string& sumo_edge,
                                          std::optional<double> offset_m);

// One preemptable approach (a stop line a light controls) seen as loop detectors would see it:
// vehicles entering its lanes are arrivals, vehicles leaving them are departures.
struct Approach {
  NodeId node;
  maps::Compass side;
  std::vector<std::string> lanes;
  double length_m = 0.0;
  std::set<std::string> vehicles;  // on the approach at the last step
  double halting = 0.0;            // halted at the last step
  double arrivals = 0.0;           // since the last report
  double departures = 0.0;
  double queue_m = 0.0;                // the longest lane's standing queue, metres from the stop line
  std::vector<std::string> detectors;  // the user's e2 detectors on its lanes
  // The user's induction loops (e1) on its lanes. Where there are some, they are the approach's
  // detectors, as in the field: loops at the stop line count departures, loops upstream count
  // arrivals, their occupancy is the approach's, and a loop with a vehicle stopped on it says the
  // queue reaches back that far.
  struct Loop {
    std::string id;
    double distance_m = 0.0;  // from the stop line
    std::set<std::string> vehicles;  // on the loop at the last step
  };
  std::vector<Loop> loops;
  double loop_occupancy = 0.0;  // the highest of its loops', 0..1, at the last step
  double loop_queue_m = 0.0;    // the furthest loop with a stopped vehicle on it
  [[nodiscard]] bool counts_departures_by_loop() const;
  [[nodiscard]] bool counts_arrivals_by_loop() const;
  // 7.5 m of lane per halted vehicle.
  [[nodiscard]] double occupancy() const { return length_m > 0.0 ? std::clamp(halting * 7.5 / length_m, 0.0, 1.0) : 0.0; }
};
std::vector<Approach> approaches_of(const SumoScenario& scenario);
// The run's SUMO files: net, background routes, the EV types, tripinfo and log, fresh for the run.
SumoLaunch launch_for(const SumoScenario& scenario, const ClosedLoopConfig& config);
// Each EV's travel time, stops and waits (result.evs, in the order of `ev_ids`, and the first EV's
// in the ev_* fields), and the other vehicles' mean time loss, from tripinfo.
void add_trip_results(const std::filesystem::path& tripinfo, const std::vector<std::string>& ev_ids, ClosedLoopResult& result);
// Updates every approach from its lanes' subscription results (vehicle ids and halting counts).
void count_lane_vehicles(const libsumo::SubscriptionResults& lanes, std::vector<Approach>& approaches);
// The user's lane-area detectors' jam lengths, where an approach has them, replace its lanes' own.
void add_detector_queues(const libsumo::SubscriptionResults& detectors, std::vector<Approach>& approaches);
// The user's induction loops' vehicles, occupancy and speed (subscription results): their counts,
// and at the report the occupancy and the queue they see, where an approach has them.
void count_loop_vehicles(const libsumo::SubscriptionResults& loops, std::vector<Approach>& approaches);
// The occupancy an approach reports: its loops' where it has any, else its halted vehicles'.
[[nodiscard]] double reported_occupancy(const Approach& a);

struct Incident {
  double time_s;
  std::string edge;
  bool applied = false;
};

// The light and link a vehicle on `lane` is taking: its connection's, where the lane is a junction's
// internal lane or the approach lane of a controlled connection; nullopt off a light.
struct LaneLink {
  std::string tls;
  int link_index = -1;
};
std::optional<LaneLink> link_of_lane(const SumoScenario& scenario, const std::string& lane, const std::string& next_edge);

// The signal controller's TraCI calls, through either API.
template <class Api>
class ApiTrafficLights final : public TrafficLightApi {
 public:
  std::string state(const std::string& tls) override { return Api::TrafficLight::getRedYellowGreenState(tls); }
  int phase(const std::string& tls) override { return Api::TrafficLight::getPhase(tls); }
  double spent_s(const std::string& tls) override {
    // SUMO 1.15 has no getSpentDuration; the phase's duration minus what is left of it.
    const double left = Api::TrafficLight::getNextSwitch(tls) - now_s;
    return std::max(0.0, Api::TrafficLight::getPhaseDuration(tls) - left);
  }
  void set_state(const std::string& tls, const std::string& state) override {
    Api::TrafficLight::setRedYellowGreenState(tls, state);
  }
  void set_program(const std::string& tls, const std::string& program_id) override {
    Api::TrafficLight::setProgram(tls, program_id);
  }
  void set_phase(const std::string& tls, int phase) override { Api::TrafficLight::setPhase(tls, phase); }

  double now_s = 0.0;  // the simulation time, needed for spent_s; set by the loop every step
};

// One EV of a run: its mission, its planner, and where SUMO has it.
struct EvRun {
  std::string id;
  EvTrip trip;
  preemption::MissionId mission = 0;
  std::vector<planner::EdgePoint> starts;
  std::vector<planner::EdgePoint> goals;
  std::optional<planner::DStarLite> dstar;
  std::vector<EdgeId> route;    // as last sent to SUMO, from the EV's edge on
  std::size_t route_index = 0;  // where the EV is on `route`
  bool added = false, seen = false, done = false;
  double depart = 0.0;
  std::string edge;  // the SUMO edge the EV is on
  double pos = 0.0;
  std::set<NodeId> preempted;
  std::size_t deferrals = 0;
  int standing_s = 0;  // steps (seconds) at a standstill, for the diagnostics
  // Time–space record: distance driven on the edges behind, and the lights of the crossings ahead.
  double driven_m = 0.0;
  std::vector<preemption::Crossing> ahead;
  std::map<NodeId, TimeSpaceSignal> seen_signals;  // sampled while ahead
  TimeSpaceTrack track;
};

// The light the EV's movement shows at a crossing: 'G' when any of its links is green, else 'y'
// when one is yellow, else 'r'.
inline char movement_light(const SumoScenario& scenario, const preemption::Crossing& c, const std::string& state) {
  const auto it = scenario.sumo_plan_of.find(c.node);
  if (it == scenario.sumo_plan_of.end()) return 'r';
  const std::string& from = scenario.graph.sumo_edge_of_arc[c.in_edge.index()];
  const std::string& to = scenario.graph.sumo_edge_of_arc[c.out_edge.index()];
  char best = 'r';
  for (std::size_t i = 0; i < it->second->links.size() && i < state.size(); ++i) {
    const maps::SumoConnection* link = it->second->links[i];
    if (link == nullptr || link->from != from || link->to != to) continue;
    if (state[i] == 'G' || state[i] == 'g') return 'G';
    if (state[i] == 'y' || state[i] == 'Y') best = 'y';
  }
  return best;
}

template <class Api, class Session>
ClosedLoopResult run_loop(const SumoScenario& scenario, const ClosedLoopConfig& config) {
  const auto& sg = scenario.graph;
  const auto& g = sg.graph;
  std::error_code ec;
  std::filesystem::create_directories(config.out_dir, ec);
  if (ec) throw SimError("cannot create " + config.out_dir.string() + ": " + ec.message());
  const double vmax_mps = config.ev_vmax_kmh / 3.6;

  planner::CostOverlay overlay(g);
  // The route knows its own preemption: the server's rule (preemption/signal_costs.hpp).
  preemption::set_signal_costs(overlay, g, scenario.plans,
                               preempts(config.signals) ? preemption::SignalCostRule::preempted : preemption::SignalCostRule::normal);
  const planner::TravelCost cost(g, overlay, {vmax_mps});

  std::vector<EvRun> evs;
  if (config.with_ev) {
    std::vector<EvTrip> trips{{config.ev_from, config.ev_to, config.ev_depart_s, config.first_priority}};
    trips.insert(trips.end(), config.more_evs.begin(), config.more_evs.end());
    for (std::size_t k = 0; k < trips.size(); ++k) {
      EvRun ev;
      ev.id = k == 0 ? std::string(kEv) : fmt::format("{}{}", kEv, k + 1);
      ev.trip = trips[k];
      ev.mission = kMission + k;
      ev.starts = points_on(sg, ev.trip.from, 0.0);
      ev.goals = points_on(sg, ev.trip.to, std::nullopt);
      ev.edge = ev.trip.from;
      ev.track.ev = ev.id;
      if (ev.starts.empty() || ev.goals.empty()) {
        throw SimError("the EV's start edge '" + ev.trip.from + "' or goal edge '" + ev.trip.to +
                       "' is not a drivable edge of the network");
      }
      evs.push_back(std::move(ev));
    }
  }

  const SumoLaunch launch = launch_for(scenario, config);
  Session bridge(launch);

  ApiTrafficLights<Api> lights_api;
  // One controller and one engine entry per light, whichever approach a claim comes from.
  SumoSignalController controller(scenario.signal_plans, scenario.sumo_plan_of, scenario.tls_phases, lights_api,
                                  scenario.actuated_tls);
  preemption::PreemptionConfig preemption_config;
  preemption_config.vicinity.enabled = config.vicinity;
  preemption::PreemptionEngine engine(g, scenario.signal_plans, controller, preemption_config);
  engine.set_signal_nodes(scenario.signal_node);

  Api::Simulation::subscribe(std::vector<int>{libsumo::VAR_COLLIDING_VEHICLES_NUMBER, libsumo::VAR_TELEPORT_STARTING_VEHICLES_NUMBER});
  for (const auto& [id, arcs] : sg.arcs_onto) Api::Edge::subscribe(id, {libsumo::VAR_CURRENT_TRAVELTIME});
  // Halting vehicles on each approach lane of a preemptable light: the congestion classifier's and
  // the vicinity rules' input; the user's lane-area detectors, where they cover a lane, instead.
  std::vector<Approach> approaches = approaches_of(scenario);
  ClosedLoopResult result;
  for (const Approach& a : approaches) {
    for (const auto& lane : a.lanes) {
      Api::Lane::subscribe(lane, {libsumo::LAST_STEP_VEHICLE_HALTING_NUMBER, libsumo::LAST_STEP_VEHICLE_ID_LIST});
    }
    for (const auto& detector : a.detectors) Api::LaneArea::subscribe(detector, {libsumo::JAM_LENGTH_METERS});
    for (const auto& loop : a.loops) {
      Api::InductionLoop::subscribe(loop.id, {libsumo::LAST_STEP_VEHICLE_ID_LIST, libsumo::LAST_STEP_OCCUPANCY,
                                              libsumo::LAST_STEP_MEAN_SPEED});
    }
    if (!a.detectors.empty()) ++result.approaches_with_detectors;
    if (!a.loops.empty()) ++result.approaches_with_loops;
  }

  double last_congestion_s = -1e9;
  // Unforeseen incidents on the first EV's free-flow route, after it has left: the same in every
  // run of a seed, the baseline without the EV included, so that they do not count as its doing.
  std::vector<Incident> incidents;
  if (config.incidents > 0) {
    const auto starts = points_on(sg, config.ev_from, 0.0);
    const auto goals = points_on(sg, config.ev_to, std::nullopt);
    planner::Rng rng(planner::derive_seed(config.seed, "incidents"));
    const planner::CostOverlay free_flow(g);
    const planner::TravelCost free_cost(g, free_flow, {vmax_mps});
    planner::OneToOneSearch search;
    const planner::Route r = starts.empty() || goals.empty() ? planner::Route{}
                                                             : search.run(planner::SearchSpace(free_cost, starts, goals), true);
    for (std::uint32_t k = 0; k < config.incidents && r.found && r.edges.size() > 3; ++k) {
      const EdgeId e = r.edges[1 + rng.below(static_cast<std::uint32_t>(r.edges.size() - 2))];
      incidents.push_back({config.ev_depart_s + rng.uniform(10.0, 60.0), sg.sumo_edge_of_arc[e.index()]});
    }
  }

  double t = 0.0;
  double last_sample_s = -1e9;
  for (int step = 0; t < config.end_s; ++step) {
    t = bridge.step();
    lights_api.now_s = t;
    const auto sim = Api::Simulation::getSubscriptionResults();
    const int colliding = static_cast<int>(as_double(sim, libsumo::VAR_COLLIDING_VEHICLES_NUMBER));
    result.collisions += colliding;
    if (colliding > 0) {
      // Each collision traced to its light: what each vehicle's link showed and whether Corridor held it.
      for (const libsumo::TraCICollision& c : Api::Simulation::getCollisions()) {
        CollisionRecord r;
        r.time_s = t;
        r.collider = c.collider;
        r.victim = c.victim;
        r.collider_type = c.colliderType;
        r.victim_type = c.victimType;
        r.kind = c.type;
        r.lane = c.lane;
        r.ev_involved = c.collider.rfind(kEv, 0) == 0 || c.victim.rfind(kEv, 0) == 0;
        const auto light_of = [&](const std::string& vehicle, char& light, std::string& lane, int& link_index) {
          try {
            lane = Api::Vehicle::getLaneID(vehicle);
            const std::vector<std::string> route = Api::Vehicle::getRoute(vehicle);
            const auto index = static_cast<std::size_t>(std::max(0, Api::Vehicle::getRouteIndex(vehicle)));
            const auto link = link_of_lane(scenario, lane, index + 1 < route.size() ? route[index + 1] : std::string{});
            if (!link) return;
            r.tls = link->tls;
            link_index = link->link_index;
            const std::string state = Api::TrafficLight::getRedYellowGreenState(link->tls);
            if (link->link_index >= 0 && static_cast<std::size_t>(link->link_index) < state.size()) light = state[static_cast<std::size_t>(link->link_index)];
          } catch (const libsumo::TraCIException&) {
            // The vehicle is gone (teleported or removed): its light is not known.
          }
        };
        light_of(c.collider, r.collider_light, r.collider_lane, r.collider_link);
        light_of(c.victim, r.victim_light, r.victim_lane, r.victim_link);
        if (!r.tls.empty()) {
          for (const auto& [node, plan] : scenario.signal_plans) {
            if (scenario.sumo_plan_of.at(node)->tls_id != r.tls) continue;
            r.held_by_corridor = controller.mode(node) == preemption::SignalMode::held;
            const auto n = static_cast<int>(plan.movements.size());
            if (r.collider_link >= 0 && r.victim_link >= 0 && r.collider_link < n && r.victim_link < n && r.collider_link != r.victim_link) {
              r.links_conflict = plan.conflicts(static_cast<std::size_t>(r.collider_link), static_cast<std::size_t>(r.victim_link));
            }
          }
        }
        spdlog::info("event=collision t={:.0f} collider={} ({}) victim={} ({}) kind={} lane={} tls={} collider_link={} ({}) "
                     "victim_link={} ({}) links_conflict={} held_by_corridor={}",
                     t, r.collider, r.collider_type, r.victim, r.victim_type, r.kind, r.lane, r.tls.empty() ? "-" : r.tls,
                     r.collider_link, r.collider_light, r.victim_link, r.victim_light, r.links_conflict, r.held_by_corridor);
        result.collision_records.push_back(std::move(r));
      }
    }
    result.teleports += static_cast<int>(as_double(sim, libsumo::VAR_TELEPORT_STARTING_VEHICLES_NUMBER));
    count_lane_vehicles(Api::Lane::getAllSubscriptionResults(), approaches);
    count_loop_vehicles(Api::InductionLoop::getAllSubscriptionResults(), approaches);

    // Measured travel times become congestion updates every period (the detection system).
    std::vector<EdgeId> changed;
    if (t - last_congestion_s >= config.congestion_period_s) {
      last_congestion_s = t;
      const auto edges = Api::Edge::getAllSubscriptionResults();
      for (const auto& [id, values] : edges) {
        const auto arcs = sg.arcs(id);
        if (arcs.empty()) continue;
        const double tt = as_double(values, libsumo::VAR_CURRENT_TRAVELTIME);
        const double free_flow = g.length_m(arcs.front()) / g.speed_mps(arcs.front());
        if (!std::isfinite(tt) || tt <= 0.0) continue;
        const double factor = std::clamp(tt / free_flow, 1.0, 50.0);
        const double old = overlay.edge(arcs.front()).congestion_factor;
        if (std::abs(factor - old) > 0.25 * old) {
          for (EdgeId arc : arcs) {
            overlay.set_edge(arc, {factor, 0.0});
            changed.push_back(arc);
          }
        }
      }
      result.congestion_updates += static_cast<std::uint32_t>(changed.size());
      add_detector_queues(Api::LaneArea::getAllSubscriptionResults(), approaches);
      // Detector counts for the queue estimate, and halting vehicles as occupancy where the
      // estimate has no data yet; the standing queue's length for the vicinity rules. Per light and
      // side: two stop lines of one light that face the same way are one approach to the engine.
      struct Measured {
        double arrivals = 0.0, departures = 0.0, occupancy = 0.0, queue_m = 0.0;
      };
      std::map<std::pair<NodeId, maps::Compass>, Measured> measured;
      for (Approach& a : approaches) {
        Measured& m = measured[{signal_of(scenario, a.node), a.side}];
        m.arrivals += a.arrivals;
        m.departures += a.departures;
        m.occupancy = std::max(m.occupancy, reported_occupancy(a));
        m.queue_m = std::max(m.queue_m, a.queue_m);
        a.arrivals = a.departures = 0.0;
      }
      for (const auto& [key, m] : measured) {
        engine.record_counts(key.first, key.second, t, m.arrivals, m.departures);
        engine.record_measurement(key.first, key.second, m.occupancy, std::nullopt);
        engine.record_queue_length(key.first, key.second, m.queue_m);
      }
    }

    for (EvRun& ev : evs) {
      if (ev.added || t < ev.trip.depart_s) continue;
      ev.dstar.emplace(cost, ev.starts, ev.goals);
      ev.dstar->replan();
      const planner::Route r = ev.dstar->route();
      if (!r.found) throw SimError("the goal of EV '" + ev.id + "' cannot be reached from its start");
      ev.route = r.edges;
      Api::Route::add(ev.id + "_route", sumo_ids(sg, ev.route));
      Api::Vehicle::add(ev.id, ev.id + "_route", ev_type(config.signals), "now", "best", "base", "max");
      Api::Vehicle::subscribe(ev.id, {libsumo::VAR_ROAD_ID, libsumo::VAR_LANEPOSITION, libsumo::VAR_SPEED});
      ev.added = true;
      ev.depart = t;
    }
    for (Incident& inc : incidents) {
      if (!inc.applied && t >= inc.time_s) {
        Api::Edge::setMaxSpeed(inc.edge, config.incident_speed_mps);
        inc.applied = true;
        spdlog::debug("event=incident t={:.0f} edge={}", t, inc.edge);
      }
    }

    const bool sample = config.record_time_space && t - last_sample_s >= 1.0 - 1e-9;
    if (sample) last_sample_s = t;
    for (EvRun& ev : evs) {
      if (!ev.added || ev.done) continue;
      const bool fresh = ev.depart == t;  // its planner already knows every update so far
      const auto state = Api::Vehicle::getSubscriptionResults(ev.id);
      if (state.empty()) {
        if (ev.seen) {
          ev.done = true;
          if (preempts(config.signals)) engine.cancel(ev.mission, t);
        }
        continue;
      }
      ev.seen = true;
      const std::string road = as_string(state, libsumo::VAR_ROAD_ID);
      if (!road.empty() && road[0] != ':' && !sg.arcs(road).empty()) {
        if (road != ev.edge) {
          // Onto a new edge: the EV has crossed the stop line of the one it left.
          const NodeId line = signal_of(scenario, sg.stop_line.at(ev.edge));
          if (preempts(config.signals)) engine.vehicle_passed(ev.mission, line, t);
          ev.driven_m += g.length_m(sg.arcs(ev.edge).front());
          if (auto it = ev.seen_signals.find(line); it != ev.seen_signals.end()) {
            it->second.distance_m = ev.driven_m;
            it->second.preempted = ev.preempted.contains(line);
            it->second.states.emplace_back(t, it->second.states.empty() ? 'r' : it->second.states.back().second);
            ev.track.signals.push_back(std::move(it->second));
            ev.seen_signals.erase(it);
          }
        }
        ev.edge = road;
        ev.pos = std::clamp(as_double(state, libsumo::VAR_LANEPOSITION), 0.0, g.length_m(sg.arcs(road).front()));
        std::size_t k = ev.route_index;
        while (k < ev.route.size() && sg.sumo_edge_of_arc[ev.route[k].index()] != ev.edge) ++k;
        if (k < ev.route.size()) ev.route_index = k;
      }
      // Why an EV stands: its lane and its leader's, every 30 s of standing (diagnostics).
      if (const double v = as_double(state, libsumo::VAR_SPEED); std::isfinite(v) && v < 0.1) {
        if (++ev.standing_s % 30 == 0) {
          const auto leader = Api::Vehicle::getLeader(ev.id, 100.0);
          std::string ahead = "none";
          if (!leader.first.empty()) {
            ahead = fmt::format("{} gap={:.1f} lane={} speed={:.1f} route_next={}", leader.first, leader.second,
                                Api::Vehicle::getLaneID(leader.first), Api::Vehicle::getSpeed(leader.first),
                                Api::Vehicle::getRoute(leader.first).size() > static_cast<std::size_t>(Api::Vehicle::getRouteIndex(leader.first)) + 1
                                    ? Api::Vehicle::getRoute(leader.first)[static_cast<std::size_t>(Api::Vehicle::getRouteIndex(leader.first)) + 1]
                                    : std::string("-"));
          }
          spdlog::info("event=ev_standing t={:.0f} ev={} lane={} pos={:.1f} standing_s={} leader={}", t, ev.id,
                       Api::Vehicle::getLaneID(ev.id), ev.pos, ev.standing_s, ahead);
        }
      } else {
        ev.standing_s = 0;
      }
      if (sample) {
        ev.track.t_s.push_back(t);
        ev.track.distance_m.push_back(ev.driven_m + ev.pos);
        const double speed = as_double(state, libsumo::VAR_SPEED);  // SUMO's invalid value before the first step
        ev.track.speed_mps.push_back(std::isfinite(speed) && speed >= 0.0 ? speed : 0.0);
      }
      planner::Route plan;
      if (config.routing == EvRouting::dynamic_route) {
        ev.dstar->move_start(points_on(sg, ev.edge, ev.pos));
        if (!changed.empty() && !fresh) ev.dstar->edges_changed(changed);
        ev.dstar->replan();
        plan = ev.dstar->route();
        if (!changed.empty() && ev.id == kEv) ++result.replans;
        // The route SUMO has from here on; setRoute must start with the EV's current edge.
        const std::vector<EdgeId> rest(ev.route.begin() + static_cast<std::ptrdiff_t>(ev.route_index), ev.route.end());
        if (plan.found && sumo_ids(sg, plan.edges) != sumo_ids(sg, rest) &&
            sg.sumo_edge_of_arc[plan.edges.front().index()] == ev.edge) {
          try {
            Api::Vehicle::setRoute(ev.id, sumo_ids(sg, plan.edges));
            ev.route = plan.edges;
            ev.route_index = 0;
            if (ev.id == kEv) ++result.route_changes;
          } catch (const libsumo::TraCIException& e) {
            spdlog::debug("event=set_route_refused t={:.0f} ev={} reason=\"{}\"", t, ev.id, e.what());
          }
        }
      } else {
        plan = planner::make_route(cost, {ev.route[ev.route_index], ev.pos},
                                   std::vector<EdgeId>(ev.route.begin() + static_cast<std::ptrdiff_t>(ev.route_index), ev.route.end()),
                                   {ev.route.back(), g.length_m(ev.route.back())});
      }
      if (plan.found) {
        ev.ahead = preemption::signalized_crossings(g, plan, scenario.plans, t);
        for (auto& c : ev.ahead) c.node = signal_of(scenario, c.node);
        if (preempts(config.signals)) engine.update_route(ev.mission, ev.trip.priority, ev.ahead, t);
      }
      if (sample) {
        for (const auto& c : ev.ahead) {
          TimeSpaceSignal& sig = ev.seen_signals[c.node];
          if (sig.tls.empty()) sig.tls = scenario.sumo_plan_of.at(c.node)->tls_id;
          const char light = movement_light(scenario, c, Api::TrafficLight::getRedYellowGreenState(sig.tls));
          if (sig.states.empty() || sig.states.back().second != light) sig.states.emplace_back(t, light);
        }
      }
    }
    if (preempts(config.signals)) {
      engine.tick(t);
      controller.update(t);
      for (const auto& event : engine.take_events()) {
        // Side-link flushes are not the EV's own lights: they count in neither its lights nor its
        // deferrals.
        if (event.side_flush) continue;
        const auto it = std::find_if(evs.begin(), evs.end(), [&](const EvRun& ev) { return ev.mission == event.mission; });
        if (event.kind == "started") {
          ++result.preemptions_started;
          if (it != evs.end()) it->preempted.insert(event.node);
        } else if (event.kind == "released") {
          ++result.preemptions_released;
        } else if (event.kind == "deferred" && it != evs.end()) {
          ++it->deferrals;
        }
      }
    }
    const bool evs_finished = std::all_of(evs.begin(), evs.end(), [](const EvRun& ev) { return ev.done; });
    const bool lights_home = controller.lights_on_program() == controller.lights_taken_over();
    if (evs_finished && lights_home && step % 10 == 0 && Api::Simulation::getMinExpectedNumber() == 0) break;
  }
  result.end_time_s = t;
  result.lights_taken_over = controller.lights_taken_over();
  result.lights_back_on_program = controller.lights_on_program();
  result.safety_violations = controller.violations();
  bridge.close();

  std::vector<std::string> ids;
  for (const EvRun& ev : evs) ids.push_back(ev.id);
  add_trip_results(launch.tripinfo, ids, result);
  for (std::size_t k = 0; k < evs.size() && k < result.evs.size(); ++k) {
    EvOutcome& o = result.evs[k];
    o.trip = evs[k].trip;
    o.deferrals = evs[k].deferrals;
    o.preempted_signals = evs[k].preempted.size();
    result.deferrals += o.deferrals;
  }
  if (!result.evs.empty()) result.preempted_signals = result.evs.front().preempted_signals;
  if (config.record_time_space && !evs.empty()) {
    std::vector<TimeSpaceTrack> tracks;
    for (EvRun& ev : evs) tracks.push_back(std::move(ev.track));
    write_time_space(config.out_dir / config.run_name, tracks,
                     fmt::format("{}: {} EV, {} routing, signals {}", scenario.name, tracks.size() == 1 ? "one" : "each",
                                 to_string(config.routing), to_string(config.signals)));
  }
  return result;
}

}  // namespace detail
}  // namespace corridor::sim
