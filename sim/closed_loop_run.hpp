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
void write_ev_types(const std::filesystem::path& file, double vmax_mps);
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
  // 7.5 m of lane per halted vehicle.
  [[nodiscard]] double occupancy() const { return length_m > 0.0 ? std::clamp(halting * 7.5 / length_m, 0.0, 1.0) : 0.0; }
};
std::vector<Approach> approaches_of(const SumoScenario& scenario);
// The run's SUMO files: net, background routes, the EV types, tripinfo and log, fresh for the run.
SumoLaunch launch_for(const SumoScenario& scenario, const ClosedLoopConfig& config);
// The EV's travel time, stops and waits, and the other vehicles' mean time loss, from tripinfo.
void add_trip_results(const std::filesystem::path& tripinfo, ClosedLoopResult& result);
// Updates every approach from its lanes' subscription results (vehicle ids and halting counts).
void count_lane_vehicles(const libsumo::SubscriptionResults& lanes, std::vector<Approach>& approaches);

struct Incident {
  double time_s;
  std::string edge;
  bool applied = false;
};

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
  preemption::set_signal_costs(overlay, scenario.plans,
                               preempts(config.signals) ? preemption::SignalCostRule::preempted : preemption::SignalCostRule::normal);
  const planner::TravelCost cost(g, overlay, {vmax_mps});
  const std::vector<planner::EdgePoint> starts = points_on(sg, config.ev_from, 0.0);
  const std::vector<planner::EdgePoint> goals = points_on(sg, config.ev_to, std::nullopt);
  if (config.with_ev && (starts.empty() || goals.empty())) {
    throw SimError("the EV's start edge '" + config.ev_from + "' or goal edge '" + config.ev_to +
                   "' is not a drivable edge of the network");
  }

  const SumoLaunch launch = launch_for(scenario, config);
  Session bridge(launch);

  ApiTrafficLights<Api> lights_api;
  SumoSignalController controller(scenario.plans, scenario.sumo_plan_of, scenario.tls_phases, lights_api);
  preemption::PreemptionEngine engine(g, scenario.plans, controller);

  Api::Simulation::subscribe(std::vector<int>{libsumo::VAR_COLLIDING_VEHICLES_NUMBER, libsumo::VAR_TELEPORT_STARTING_VEHICLES_NUMBER});
  for (const auto& [id, arcs] : sg.arcs_onto) Api::Edge::subscribe(id, {libsumo::VAR_CURRENT_TRAVELTIME});
  // Halting vehicles on each approach lane of a preemptable light: the congestion classifier's input.
  std::vector<Approach> approaches = approaches_of(scenario);
  for (const Approach& a : approaches) {
    for (const auto& lane : a.lanes) {
      Api::Lane::subscribe(lane, {libsumo::LAST_STEP_VEHICLE_HALTING_NUMBER, libsumo::LAST_STEP_VEHICLE_ID_LIST});
    }
  }

  ClosedLoopResult result;
  std::optional<planner::DStarLite> dstar;
  std::vector<EdgeId> route;       // as last sent to SUMO, from the EV's edge on
  std::size_t route_index = 0;     // where the EV is on `route`
  bool ev_added = false, ev_seen = false, ev_done = false;
  double ev_depart = 0.0;
  std::string ev_edge = config.ev_from;  // the SUMO edge the EV is on
  double ev_pos = 0.0;
  double last_congestion_s = -1e9;
  // Unforeseen incidents on the EV's free-flow route, after it has left: the same in every run of a
  // seed, the baseline without the EV included, so that they do not count as the EV's doing.
  std::vector<Incident> incidents;
  if (!starts.empty() && !goals.empty() && config.incidents > 0) {
    planner::Rng rng(planner::derive_seed(config.seed, "incidents"));
    const planner::CostOverlay free_flow(g);
    const planner::TravelCost free_cost(g, free_flow, {vmax_mps});
    planner::OneToOneSearch search;
    const planner::Route r = search.run(planner::SearchSpace(free_cost, starts, goals), true);
    for (std::uint32_t k = 0; k < config.incidents && r.found && r.edges.size() > 3; ++k) {
      const EdgeId e = r.edges[1 + rng.below(static_cast<std::uint32_t>(r.edges.size() - 2))];
      incidents.push_back({config.ev_depart_s + rng.uniform(10.0, 60.0), sg.sumo_edge_of_arc[e.index()]});
    }
  }
  std::set<NodeId> preempted;

  double t = 0.0;
  for (int step = 0; t < config.end_s; ++step) {
    t = bridge.step();
    lights_api.now_s = t;
    const auto sim = Api::Simulation::getSubscriptionResults();
    result.collisions += static_cast<int>(as_double(sim, libsumo::VAR_COLLIDING_VEHICLES_NUMBER));
    result.teleports += static_cast<int>(as_double(sim, libsumo::VAR_TELEPORT_STARTING_VEHICLES_NUMBER));
    count_lane_vehicles(Api::Lane::getAllSubscriptionResults(), approaches);

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
      for (Approach& a : approaches) {
        // Detector counts for the queue estimate, and halting vehicles as occupancy where the
        // estimate has no data yet.
        engine.record_counts(a.node, a.side, t, a.arrivals, a.departures);
        a.arrivals = a.departures = 0.0;
        engine.record_measurement(a.node, a.side, a.occupancy(), std::nullopt);
      }
    }

    if (config.with_ev && !ev_added && t >= config.ev_depart_s) {
      dstar.emplace(cost, starts, goals);
      dstar->replan();
      const planner::Route r = dstar->route();
      if (!r.found) throw SimError("the EV's goal cannot be reached from its start");
      route = r.edges;
      Api::Route::add("ev_route", sumo_ids(sg, route));
      Api::Vehicle::add(kEv, "ev_route", ev_type(config.signals), "now",
                             "best", "base", "max");
      Api::Vehicle::subscribe(kEv, {libsumo::VAR_ROAD_ID, libsumo::VAR_LANEPOSITION, libsumo::VAR_SPEED});
      ev_added = true;
      ev_depart = t;
      changed.clear();  // the new planner already knows every update so far
    }
    for (Incident& inc : incidents) {
      if (!inc.applied && t >= inc.time_s) {
        Api::Edge::setMaxSpeed(inc.edge, config.incident_speed_mps);
        inc.applied = true;
        spdlog::debug("event=incident t={:.0f} edge={}", t, inc.edge);
      }
    }

    if (ev_added && !ev_done) {
      const auto ev = Api::Vehicle::getSubscriptionResults(kEv);
      if (ev.empty()) {
        if (ev_seen) {
          ev_done = true;
          result.ev_arrived = true;
          result.ev_travel_time_s = t - ev_depart;
          if (preempts(config.signals)) engine.cancel(kMission, t);
        }
      } else {
        ev_seen = true;
        const std::string road = as_string(ev, libsumo::VAR_ROAD_ID);
        if (!road.empty() && road[0] != ':' && !sg.arcs(road).empty()) {
          if (road != ev_edge && preempts(config.signals)) {
            // Onto a new edge: the EV has crossed the stop line of the one it left.
            engine.vehicle_passed(kMission, sg.stop_line.at(ev_edge), t);
          }
          ev_edge = road;
          ev_pos = std::clamp(as_double(ev, libsumo::VAR_LANEPOSITION), 0.0, g.length_m(sg.arcs(road).front()));
          std::size_t k = route_index;
          while (k < route.size() && sg.sumo_edge_of_arc[route[k].index()] != ev_edge) ++k;
          if (k < route.size()) route_index = k;
        }
        planner::Route plan;
        if (config.routing == EvRouting::dynamic_route) {
          dstar->move_start(points_on(sg, ev_edge, ev_pos));
          if (!changed.empty()) dstar->edges_changed(changed);
          dstar->replan();
          plan = dstar->route();
          if (!changed.empty()) ++result.replans;
          // The route SUMO has from here on; setRoute must start with the EV's current edge.
          const std::vector<EdgeId> ahead(route.begin() + static_cast<std::ptrdiff_t>(route_index), route.end());
          if (plan.found && sumo_ids(sg, plan.edges) != sumo_ids(sg, ahead) &&
              sg.sumo_edge_of_arc[plan.edges.front().index()] == ev_edge) {
            try {
              Api::Vehicle::setRoute(kEv, sumo_ids(sg, plan.edges));
              route = plan.edges;
              route_index = 0;
              ++result.route_changes;
            } catch (const libsumo::TraCIException& e) {
              spdlog::debug("event=set_route_refused t={:.0f} reason=\"{}\"", t, e.what());
            }
          }
        } else {
          plan = planner::make_route(cost, {route[route_index], ev_pos},
                                     std::vector<EdgeId>(route.begin() + static_cast<std::ptrdiff_t>(route_index), route.end()),
                                     {route.back(), g.length_m(route.back())});
        }
        if (preempts(config.signals) && plan.found) {
          const auto crossings = preemption::signalized_crossings(plan, scenario.plans, t);
          engine.update_route(kMission, 1, crossings, t);
        }
      }
    }
    if (preempts(config.signals)) {
      engine.tick(t);
      controller.update(t);
      for (const auto& ev : engine.take_events()) {
        if (ev.kind == "started") {
          ++result.preemptions_started;
          preempted.insert(ev.node);
        } else if (ev.kind == "released") {
          ++result.preemptions_released;
        }
      }
    }
    const bool ev_finished = !config.with_ev || ev_done;
    const bool lights_home = controller.lights_on_program() == controller.lights_taken_over();
    if (ev_finished && lights_home && step % 10 == 0 && Api::Simulation::getMinExpectedNumber() == 0) break;
  }
  result.end_time_s = t;
  result.preempted_signals = preempted.size();
  result.lights_taken_over = controller.lights_taken_over();
  result.lights_back_on_program = controller.lights_on_program();
  result.safety_violations = controller.violations();
  bridge.close();

  add_trip_results(launch.tripinfo, result);
  return result;
}


}  // namespace detail
}  // namespace corridor::sim
