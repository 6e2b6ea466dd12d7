// The closed loop through a running `corridor serve`: SUMO runs here, at wall-clock pace, and the
// server does the rest through its HTTP API, as it would for a real vehicle. It gets the EV's
// positions and the measured congestion, plans and replans the mission, and runs preemption. Its
// held and clearing lights are mirrored onto SUMO's traffic lights.
#include <libsumo/libtraci.h>

#include <chrono>
#include <cmath>
#include <optional>
#include <map>
#include <thread>

#include <random>

#include "localizer/fusion/gps_odometry_localizer.hpp"
#include "ntcip/virtual_agents.hpp"
#include "localizer/fusion/simulated_odometry.hpp"
#include "sim/closed_loop_run.hpp"
#include "sim/corridor_client.hpp"

namespace corridor::sim {
namespace {

using nlohmann::json;

std::vector<std::string> sumo_route_of(const maps::SumoGraph& sg, const json& mission) {
  std::vector<std::string> ids;
  if (!mission.contains("route") || mission["route"].is_null()) return ids;
  // at() throws on a malformed answer rather than reading what is not there.
  for (const auto& e : mission.at("route").at("properties").at("edges")) {
    const auto arc = e.get<std::uint32_t>();
    if (arc >= sg.sumo_edge_of_arc.size()) throw SimError("the server's route names an edge this net does not have");
    ids.push_back(sg.sumo_edge_of_arc[arc]);
  }
  return ids;
}

json position_json(const maps::RoadGraph& g, maps::Point2 p, double heading_deg, double speed_mps, double time_s) {
  const maps::LatLon at = g.projection().to_lat_lon(p);
  return {{"lat", at.lat_deg}, {"lon", at.lon_deg}, {"heading_deg", heading_deg}, {"speed_mps", speed_mps},
          {"timestamp", time_s}, {"source", "gps"}};
}

double wall_s() { return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count(); }

struct TraciLightsApi {
  using TrafficLight = libtraci::TrafficLight;
};

// The scenario's lights as a SignalMap, keyed as the server keys a SUMO net's (maps::sumo_signal_map).
maps::SignalMap signal_map_of(const SumoScenario& s) {
  maps::SignalMap m;
  m.plans = s.plans;
  m.signals = s.signal_plans;
  m.signal_of = s.signal_node;
  for (const auto& [key, plan] : s.signal_plans) m.names.emplace(key, s.sumo_plan_of.at(key)->tls_id);
  return m;
}

}  // namespace

ClosedLoopResult run_closed_loop_server(const SumoScenario& scenario, const ClosedLoopConfig& config) {
  using namespace detail;
  if (config.routing != EvRouting::dynamic_route || !preempts(config.signals) || !config.with_ev) {
    throw SimError("--server runs the server's own loop: dynamic routing with Corridor preemption and an EV");
  }
  const auto& sg = scenario.graph;
  const auto& g = sg.graph;
  CorridorClient server(config.server_url, config.server_token);
  const json health = server.get("/v1/health");
  const json server_map = health.is_object() ? health.value("map", json::object()) : json::object();
  if (server_map.value("nodes", std::size_t{0}) != g.node_count() || server_map.value("edges", std::size_t{0}) != g.edge_count()) {
    throw SimError("the server's map (" + server_map.dump() + ") is not this SUMO network; start it with --map " +
                   scenario.net_file.string());
  }
  std::error_code ec;
  std::filesystem::create_directories(config.out_dir, ec);
  const auto starts = points_on(sg, config.ev_from, 0.0);
  const auto goals = points_on(sg, config.ev_to, std::nullopt);
  if (starts.empty() || goals.empty()) throw SimError("the EV's start or goal edge is not a drivable edge of the network");

  const SumoLaunch launch = launch_for(scenario, config);
  SumoBridge bridge(launch);

  // NTCIP: SUMO's lights behind virtual controllers the server drives over SNMP. The agents run on
  // this thread, between steps and while the loop waits for the wall clock, in simulation time.
  detail::ApiTrafficLights<TraciLightsApi> lights_api;
  std::optional<SumoSignalController> field_lights;
  std::optional<maps::SignalMap> signal_map;
  std::optional<ntcip::VirtualAgents> agents;
  if (config.ntcip) {
    field_lights.emplace(scenario.signal_plans, scenario.sumo_plan_of, scenario.tls_phases, lights_api, scenario.actuated_tls);
    signal_map.emplace(signal_map_of(scenario));
    ntcip::VirtualAgentsConfig agents_config;
    agents_config.host = config.ntcip_host;
    agents_config.first_port = config.ntcip_port;
    agents_config.security.read_community = config.read_community;
    agents_config.security.write_community = config.write_community;
    agents_config.security.state_dir = config.out_dir / (config.run_name + ".snmp");
    agents_config.security.engine_name = "corridor-" + std::to_string(config.ntcip_port);
    agents.emplace(g, *signal_map, *field_lights, agents_config, bridge.time_s());
    spdlog::info("event=ntcip_agents count={} first_port={}", agents->manifest().size(), config.ntcip_port);
  }

  libtraci::Simulation::subscribe(std::vector<int>{libsumo::VAR_COLLIDING_VEHICLES_NUMBER, libsumo::VAR_TELEPORT_STARTING_VEHICLES_NUMBER});
  for (const auto& [id, arcs] : sg.arcs_onto) libtraci::Edge::subscribe(id, {libsumo::VAR_CURRENT_TRAVELTIME});
  std::vector<double> factor(g.edge_count(), 1.0);
  std::vector<Approach> approaches = approaches_of(scenario);
  ClosedLoopResult result;
  for (const Approach& a : approaches) {
    for (const auto& lane : a.lanes) {
      libtraci::Lane::subscribe(lane, {libsumo::LAST_STEP_VEHICLE_HALTING_NUMBER, libsumo::LAST_STEP_VEHICLE_ID_LIST});
    }
    for (const auto& detector : a.detectors) libtraci::LaneArea::subscribe(detector, {libsumo::JAM_LENGTH_METERS});
    for (const auto& loop : a.loops) {
      libtraci::InductionLoop::subscribe(loop.id, {libsumo::LAST_STEP_VEHICLE_ID_LIST, libsumo::LAST_STEP_OCCUPANCY,
                                                   libsumo::LAST_STEP_MEAN_SPEED});
    }
    if (!a.detectors.empty()) ++result.approaches_with_detectors;
    if (!a.loops.empty()) ++result.approaches_with_loops;
  }

  const std::string vehicle = "ev-" + config.run_name;
  // The EV's receiver and onboard localizer (only with gps_noise_m > 0).
  const maps::EdgeSnapper snapper(g);
  localizer::GpsOdometryLocalizer onboard(g, snapper);
  std::mt19937_64 rng(config.seed * 7919 + 3);
  std::normal_distribution<double> gauss(0.0, 1.0);
  localizer::SimulatedOdometry odometry({}, config.seed * 7919 + 5);
  std::optional<std::pair<maps::Point2, double>> last_truth;  // position, angle
  double last_fix_s = -1e9;
  std::optional<std::uint64_t> mission;
  std::vector<std::string> route;
  bool ev_added = false, ev_seen = false, ev_done = false;
  double ev_depart = 0.0;
  double last_congestion_s = -1e9;
  std::map<std::uint32_t, std::string> taken_over;  // signal node -> tls, while the server holds it
  std::set<std::uint32_t> preempted;
  std::size_t restored = 0;
  const double wall_start = wall_s();
  const double begin_s = scenario.config ? scenario.config->begin_s : 0.0;  // a user's scenario starts there
  double t = begin_s;
  for (int step = 0; t < config.end_s; ++step) {
    // SUMO keeps pace with the wall clock, which the server's schedule runs on.
    const double due = wall_start + (t - begin_s);
    if (agents) {
      // The controllers keep answering while the loop waits for the wall clock.
      for (double wait = due - wall_s(); wait > 0; wait = due - wall_s()) agents->poll(static_cast<int>(std::ceil(wait * 1000.0)), t);
    } else if (const double wait = due - wall_s(); wait > 0) {
      std::this_thread::sleep_for(std::chrono::duration<double>(wait));
    }
    t = bridge.step();
    lights_api.now_s = t;
    if (agents) {
      field_lights->update(t);
      agents->poll(0, t);
    }
    // The same clock as `due`: a scenario that begins at 07:00 is not seven hours ahead of the
    // server's, which refuses positions from further ahead than its clock skew allows.
    const double now = wall_start + (t - begin_s);
    const auto sim = libtraci::Simulation::getSubscriptionResults();
    result.collisions += static_cast<int>(as_double(sim, libsumo::VAR_COLLIDING_VEHICLES_NUMBER));
    result.teleports += static_cast<int>(as_double(sim, libsumo::VAR_TELEPORT_STARTING_VEHICLES_NUMBER));
    count_lane_vehicles(libtraci::Lane::getAllSubscriptionResults(), approaches);
    count_loop_vehicles(libtraci::InductionLoop::getAllSubscriptionResults(), approaches);

    if (t - last_congestion_s >= config.congestion_period_s) {
      last_congestion_s = t;
      json updates = json::array();
      for (const auto& [id, values] : libtraci::Edge::getAllSubscriptionResults()) {
        const auto arcs = sg.arcs(id);
        if (arcs.empty()) continue;
        const double tt = as_double(values, libsumo::VAR_CURRENT_TRAVELTIME);
        if (!std::isfinite(tt) || tt <= 0.0) continue;
        const double f = std::clamp(tt / (g.length_m(arcs.front()) / g.speed_mps(arcs.front())), 1.0, 50.0);
        if (std::abs(f - factor[arcs.front().index()]) <= 0.25 * factor[arcs.front().index()]) continue;
        for (EdgeId arc : arcs) {
          factor[arc.index()] = f;
          updates.push_back({{"edge", arc.v}, {"factor", f}});
        }
      }
      // The approaches' detector reports, as a detector feed with the sensor role sends them:
      // counts, occupancy and the standing queue (the user's e2 jam lengths where they have them),
      // so that the server's engine runs vicinity-aware preemption as the in-process loop does.
      add_detector_queues(libtraci::LaneArea::getAllSubscriptionResults(), approaches);
      for (Approach& a : approaches) {
        server.post("/v1/signals/" + std::to_string(a.node.v) + "/counts",
                    {{"approach", std::string(1, maps::compass_letter(a.side))}, {"arrivals", a.arrivals}, {"departures", a.departures},
                     {"occupancy", reported_occupancy(a)}, {"queue_m", a.queue_m}});
        a.arrivals = a.departures = 0.0;
      }
      if (!updates.empty()) {
        const json res = server.post("/v1/congestion", {{"updates", updates}});
        result.congestion_updates += static_cast<std::uint32_t>(updates.size());
        result.replans += res.value("missions_replanned", 0u);
      }
    }

    if (!ev_added && t >= config.ev_depart_s) {
      // Where the EV stands, then a mission from there: the server snaps with the heading.
      const EdgeId first = starts.front().edge;
      const maps::Point2 a = g.point_along(first, 1.0), b = g.point_along(first, 6.0);
      const double heading = std::fmod(std::atan2(b.x_m - a.x_m, b.y_m - a.y_m) * 180.0 / M_PI + 360.0, 360.0);
      server.post("/v1/vehicles/" + path_segment(vehicle) + "/position", position_json(g, a, heading, 0.0, now));
      const maps::LatLon dest = g.projection().to_lat_lon(g.point_along(goals.front().edge, g.length_m(goals.front().edge) - 1.0));
      const json m = server.post("/v1/missions", {{"vehicle_id", vehicle},
                                                  {"destination", {{"lat", dest.lat_deg}, {"lon", dest.lon_deg}}},
                                                  {"priority", 1},
                                                  {"vmax_kmh", config.ev_vmax_kmh}});
      mission = m.at("id").get<std::uint64_t>();
      route = sumo_route_of(sg, m);
      if (route.empty() || route.front() != config.ev_from) {
        throw SimError("the server planned from '" + (route.empty() ? std::string("nothing") : route.front()) + "', not from the EV's edge '" +
                       config.ev_from + "'");
      }
      libtraci::Route::add("ev_route", route);
      libtraci::Vehicle::add(kEv, "ev_route", ev_type(config.signals), "now", "best", "base", "max");
      libtraci::Vehicle::subscribe(kEv, {libsumo::VAR_ROAD_ID, libsumo::VAR_POSITION, libsumo::VAR_ANGLE, libsumo::VAR_SPEED});
      ev_added = true;
      ev_depart = t;
    }

    if (ev_added && !ev_done) {
      const auto ev = libtraci::Vehicle::getSubscriptionResults(kEv);
      if (ev.empty()) {
        if (ev_seen) {
          ev_done = true;
          result.ev_arrived = true;
          result.ev_travel_time_s = t - ev_depart;
        }
      } else {
        ev_seen = true;
        const std::string road = as_string(ev, libsumo::VAR_ROAD_ID);
        const auto pos = std::dynamic_pointer_cast<libsumo::TraCIPosition>(ev.at(libsumo::VAR_POSITION));
        std::optional<json> report;
        const double sumo_angle = as_double(ev, libsumo::VAR_ANGLE);
        // SUMO reports an invalid value (-2^30) before the vehicle is on the road.
        if (pos && config.gps_noise_m > 0.0 && !road.empty() && sumo_angle >= 0.0 && sumo_angle <= 360.0) {
          // The receiver and the onboard localizer: odometry every step, a fix at the GPS rate.
          const maps::Point2 truth{pos->x, pos->y};
          const double angle = sumo_angle;
          const double speed = as_double(ev, libsumo::VAR_SPEED);
          // The straight line between two steps: the loop runs SUMO's default (Euler) update, where
          // the step's speeds are not the distance it moved (a braking step moves by the new speed).
          if (last_truth) onboard.on_odometry(odometry.step(t, last_truth->first, last_truth->second, truth, angle));
          last_truth = {truth, angle};
          const double since = t - ev_depart;
          const bool out = std::any_of(config.gps_outages.begin(), config.gps_outages.end(),
                                       [&](const auto& w) { return since >= w.first && since < w.second; });
          if (t - last_fix_s >= 1.0 / config.gps_rate_hz - 1e-9) {
            last_fix_s = t;
            const double sigma = out ? 40.0 : config.gps_noise_m;  // multipath under a roof of buildings
            const maps::Point2 noisy{truth.x_m + sigma * gauss(rng), truth.y_m + sigma * gauss(rng)};
            const double hdop = out ? 15.0 : std::max(1.0, config.gps_noise_m / 4.0);
            // The receiver's course (±5°) and Doppler speed (±0.3 m/s), reported to the server and
            // used on board (the odometry's scale is calibrated against the speed).
            const double course = std::fmod(angle + 5.0 * gauss(rng) + 360.0, 360.0);
            const double doppler = std::max(0.0, speed + 0.3 * gauss(rng));
            json fix = position_json(g, noisy, course, doppler, now);
            fix["hdop"] = hdop;
            localizer::GpsFix f;
            f.time_s = t;
            f.position = g.projection().to_lat_lon(noisy);
            f.hdop = hdop;
            f.speed_mps = doppler;
            if (speed > 3.0) f.heading_deg = course;
            onboard.on_gps(f);
            if (!out) {
              report = std::move(fix);
            } else {
              // The bad fix is reported honestly (the server stores it as low_accuracy) and the
              // onboard odometry's position follows as source "vo".
              (void)server.post("/v1/vehicles/" + path_segment(vehicle) + "/position", fix);
              const localizer::LocalizedPoint& p = onboard.last();
              if (p.source == localizer::PositionSource::odometry) {
                json vo = position_json(g, p.match.point, p.heading_deg, as_double(ev, libsumo::VAR_SPEED), now + 1e-3);
                vo["source"] = "vo";
                report = std::move(vo);
              }
            }
          }
        } else if (!road.empty() && road[0] != ':' && pos) {
          report = position_json(g, {pos->x, pos->y}, as_double(ev, libsumo::VAR_ANGLE), as_double(ev, libsumo::VAR_SPEED), now);
        }
        if (report) {
          const json res = server.post("/v1/vehicles/" + path_segment(vehicle) + "/position", *report);
          if (res.value("route_changed", false) && mission) {
            const auto fresh = sumo_route_of(sg, server.get("/v1/missions/" + std::to_string(*mission)));
            if (!fresh.empty() && fresh.front() == road && fresh != route) {
              try {
                libtraci::Vehicle::setRoute(kEv, fresh);
                route = fresh;
                ++result.route_changes;
              } catch (const libsumo::TraCIException& e) {
                spdlog::debug("event=set_route_refused t={:.0f} reason=\"{}\"", t, e.what());
              }
            }
          }
        }
      }
    }

    // Mirror the server's signals: held and clearing lights are shown as the server shows them;
    // back on its program, the light gets SUMO's program again at the server's step. Through
    // NTCIP the agents drive the lights instead.
    const json signals = agents ? json{{"signals", json::array()}} : server.get("/v1/signals");
    for (const auto& s : signals.at("signals")) {
      const auto node = s.at("id").get<std::uint32_t>();
      const std::string mode = s.at("mode");
      const auto sp = scenario.sumo_plan_of.find(NodeId{node});
      if (sp == scenario.sumo_plan_of.end()) continue;
      // A light is taken over when the server holds it, and followed through the clearance after.
      if (mode == "held" || (mode == "clearing" && taken_over.contains(node))) {
        std::string state;
        for (const auto& l : s.at("lights")) {
          const std::string light = l.at("light");
          state += light == "green" ? 'G' : light == "yellow" ? 'y' : 'r';
        }
        libtraci::TrafficLight::setRedYellowGreenState(sp->second->tls_id, state);
        if (mode == "held") preempted.insert(node);
        taken_over[node] = sp->second->tls_id;
      } else if (const auto it = taken_over.find(node); it != taken_over.end()) {
        const auto& phases = scenario.tls_phases.at(it->second);
        const auto program_step = s.at("program_step").get<std::size_t>();
        int sumo_phase = 0;
        for (std::size_t i = 0, k = 0; i < phases.size(); ++i) {
          const auto& st = phases[i].state;
          if (st.find_first_of("Gg") == std::string::npos || st.find_first_of("yY") != std::string::npos) continue;
          if (k++ == program_step) {
            sumo_phase = static_cast<int>(i);
            break;
          }
        }
        libtraci::TrafficLight::setProgram(it->second, sp->second->program_id);
        libtraci::TrafficLight::setPhase(it->second, sumo_phase);
        taken_over.erase(it);
        ++restored;
      }
    }
    const bool lights_home = !field_lights || field_lights->lights_on_program() == field_lights->lights_taken_over();
    if (ev_done && taken_over.empty() && lights_home && step % 10 == 0 && libtraci::Simulation::getMinExpectedNumber() == 0) break;
    if (ev_done && taken_over.empty() && lights_home && t > ev_depart + result.ev_travel_time_s + 10.0) break;
  }
  result.end_time_s = t;
  result.preempted_signals = preempted.size();
  result.preemptions_started = preempted.size();
  result.preemptions_released = restored;
  result.lights_taken_over = restored + taken_over.size();
  result.lights_back_on_program = restored;
  if (field_lights) {
    // What the agents' lights did: every hold they reached, and their audit.
    result.lights_taken_over = field_lights->lights_taken_over();
    result.lights_back_on_program = field_lights->lights_on_program();
    result.preemptions_started = field_lights->holds_reached();
    result.preemptions_released = field_lights->programs_restored();
    result.safety_violations = field_lights->violations();
    result.preempted_signals = field_lights->lights_taken_over();
  }
  bridge.close();
  add_trip_results(launch.tripinfo, {kEv}, result);
  return result;
}

}  // namespace corridor::sim
