#include "sim/closed_loop.hpp"

#include <libsumo/libtraci.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <fstream>
#include <set>

#include "maps/intersection_geometry.hpp"
#include "planner/dstar_lite.hpp"
#include "planner/experiments/scenario_generator.hpp"
#include "planner/one_to_one_search.hpp"
#include "preemption/engine.hpp"
#include "sim/errors.hpp"
#include "sim/sumo_bridge.hpp"
#include "sim/sumo_signal_controller.hpp"
#include "sim/tripinfo.hpp"

namespace corridor::sim {
namespace {

constexpr const char* kEv = "ev";
constexpr preemption::MissionId kMission = 1;

double as_double(const libsumo::TraCIResults& r, int var) {
  const auto it = r.find(var);
  if (it == r.end()) return std::nan("");
  if (auto d = std::dynamic_pointer_cast<libsumo::TraCIDouble>(it->second)) return d->value;
  if (auto i = std::dynamic_pointer_cast<libsumo::TraCIInt>(it->second)) return i->value;
  return std::nan("");
}

std::string as_string(const libsumo::TraCIResults& r, int var) {
  const auto it = r.find(var);
  if (it == r.end()) return {};
  if (auto s = std::dynamic_pointer_cast<libsumo::TraCIString>(it->second)) return s->value;
  return {};
}

void write_ev_types(const std::filesystem::path& file, double vmax_mps) {
  std::ofstream out(file, std::ios::trunc);
  // The EV drives at the speed limit (speedFactor 1), like the planner's cost model, up to vmax.
  // The bluelight type may pass red lights slowly, as SUMO users configure it.
  out << fmt::format(
      "<additional>\n"
      "  <vType id=\"ev\" vClass=\"emergency\" guiShape=\"emergency\" color=\"1,0,0\" maxSpeed=\"{0:.3f}\" "
      "speedFactor=\"1\" speedDev=\"0\"/>\n"
      "  <vType id=\"ev_bluelight\" vClass=\"emergency\" guiShape=\"emergency\" color=\"0,0,1\" maxSpeed=\"{0:.3f}\" "
      "speedFactor=\"1\" speedDev=\"0\" jmDriveAfterRedTime=\"300\" jmDriveRedSpeed=\"5.56\">\n"
      "    <param key=\"has.bluelight.device\" value=\"true\"/>\n"
      "  </vType>\n"
      "</additional>\n",
      vmax_mps);
  if (!out) throw SimError("cannot write " + file.string());
}

std::vector<std::string> sumo_ids(const maps::SumoGraph& g, std::span<const EdgeId> arcs) {
  std::vector<std::string> ids;
  for (EdgeId e : arcs) ids.push_back(g.sumo_edge_of_arc[e.index()]);
  return ids;
}

// Every graph edge that puts the vehicle on `sumo_edge`, at `offset_m` (one per way onto it).
std::vector<planner::EdgePoint> points_on(const maps::SumoGraph& g, const std::string& sumo_edge, std::optional<double> offset_m) {
  std::vector<planner::EdgePoint> points;
  for (EdgeId arc : g.arcs(sumo_edge)) points.push_back({arc, offset_m.value_or(g.graph.length_m(arc))});
  return points;
}

struct Incident {
  double time_s;
  std::string edge;
  bool applied = false;
};

}  // namespace

const char* to_string(EvRouting r) { return r == EvRouting::static_route ? "static" : "dynamic"; }
const char* to_string(EvSignals s) {
  switch (s) {
    case EvSignals::none: return "none";
    case EvSignals::bluelight: return "bluelight";
    case EvSignals::corridor: return "corridor";
  }
  return "?";
}

std::pair<std::string, std::string> pick_ev_trip(const SumoScenario& scenario, std::uint64_t seed) {
  const auto& g = scenario.graph.graph;
  planner::Rng rng(planner::derive_seed(seed, "ev-trip/" + scenario.name));
  const double diagonal = maps::distance_m(g.min_corner(), g.max_corner());
  const planner::CostOverlay overlay(g);
  const planner::TravelCost cost(g, overlay, {});
  planner::OneToOneSearch search;
  const auto m = static_cast<std::uint32_t>(g.edge_count());
  for (int attempt = 0; attempt < 20000; ++attempt) {
    const EdgeId a{rng.below(m)};
    const EdgeId b{rng.below(m)};
    const double d = maps::distance_m(g.point_along(a, 0.0), g.point_along(b, g.length_m(b)));
    if (a == b || d < 0.5 * diagonal * (1.0 - attempt / 40000.0)) continue;
    const planner::SearchSpace space(cost, {{a, 0.0}}, {{b, g.length_m(b)}});
    const planner::Route r = search.run(space, true);
    // A trip that crosses at least one traffic light, where the net has any: preemption is the point.
    const bool crosses_light = scenario.plans.empty() || std::any_of(r.nodes.begin(), r.nodes.end(), [&](NodeId v) {
                                 return scenario.plans.contains(v);
                               });
    if (r.found && r.edges.size() >= 4 && (crosses_light || attempt > 15000)) {
      return {scenario.graph.sumo_edge_of_arc[a.index()], scenario.graph.sumo_edge_of_arc[b.index()]};
    }
  }
  throw SimError("no connected start/goal pair for the emergency vehicle on " + scenario.name);
}

ClosedLoopResult run_closed_loop(const SumoScenario& scenario, const ClosedLoopConfig& config) {
  const auto& sg = scenario.graph;
  const auto& g = sg.graph;
  std::error_code ec;
  std::filesystem::create_directories(config.out_dir, ec);
  if (ec) throw SimError("cannot create " + config.out_dir.string() + ": " + ec.message());
  const double vmax_mps = config.ev_vmax_kmh / 3.6;

  planner::CostOverlay overlay(g);
  const planner::TravelCost cost(g, overlay, {vmax_mps});
  const std::vector<planner::EdgePoint> starts = points_on(sg, config.ev_from, 0.0);
  const std::vector<planner::EdgePoint> goals = points_on(sg, config.ev_to, std::nullopt);
  if (config.with_ev && (starts.empty() || goals.empty())) {
    throw SimError("the EV's start edge '" + config.ev_from + "' or goal edge '" + config.ev_to +
                   "' is not a drivable edge of the network");
  }

  SumoLaunch launch;
  launch.net = scenario.net_file;
  if (!config.background_routes.empty()) launch.routes.push_back(config.background_routes);
  const auto types = config.out_dir / "ev_types.add.xml";
  write_ev_types(types, vmax_mps);
  launch.additional.push_back(types);
  launch.tripinfo = config.out_dir / (config.run_name + ".tripinfo.xml");
  launch.log = config.out_dir / (config.run_name + ".sumo.log");
  launch.end_s = config.end_s;
  launch.seed = config.seed;
  std::filesystem::remove(launch.tripinfo, ec);
  std::filesystem::remove(launch.log, ec);
  SumoBridge bridge(launch);

  TraciTrafficLights lights_api;
  SumoSignalController controller(scenario.plans, scenario.sumo_plan_of, scenario.tls_phases, lights_api);
  preemption::PreemptionEngine engine(g, scenario.plans, controller);

  libtraci::Simulation::subscribe(std::vector<int>{libsumo::VAR_COLLIDING_VEHICLES_NUMBER, libsumo::VAR_TELEPORT_STARTING_VEHICLES_NUMBER});
  for (const auto& [id, arcs] : sg.arcs_onto) libtraci::Edge::subscribe(id, {libsumo::VAR_CURRENT_TRAVELTIME});
  // Halting vehicles on each approach lane of a preemptable light: the congestion classifier's input.
  struct Approach {
    NodeId node;
    maps::Compass side;
    std::vector<std::string> lanes;
    double length_m = 0.0;
  };
  std::vector<Approach> approaches;
  for (const auto& [node, plan] : scenario.plans) {
    // A plan node is one approach's stop line.
    if (g.in_edges(node).empty()) continue;
    {
      const maps::SumoEdge* se = scenario.net.edge(sg.sumo_edge_of_node[node.index()]);
      if (se == nullptr) continue;
      Approach a{node, maps::approach_side(g, g.in_edges(node).front()), {}, 0.0};
      for (const auto& lane : se->lanes) {
        a.lanes.push_back(lane.id);
        a.length_m += lane.length_m;
        libtraci::Lane::subscribe(lane.id, {libsumo::LAST_STEP_VEHICLE_HALTING_NUMBER});
      }
      approaches.push_back(std::move(a));
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
    const auto sim = libtraci::Simulation::getSubscriptionResults();
    result.collisions += static_cast<int>(as_double(sim, libsumo::VAR_COLLIDING_VEHICLES_NUMBER));
    result.teleports += static_cast<int>(as_double(sim, libsumo::VAR_TELEPORT_STARTING_VEHICLES_NUMBER));

    // Measured travel times become congestion updates every period (the detection system).
    std::vector<EdgeId> changed;
    if (t - last_congestion_s >= config.congestion_period_s) {
      last_congestion_s = t;
      const auto edges = libtraci::Edge::getAllSubscriptionResults();
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
      const auto lanes = libtraci::Lane::getAllSubscriptionResults();
      for (const Approach& a : approaches) {
        double halting = 0.0;
        for (const auto& lane : a.lanes) {
          if (const auto it = lanes.find(lane); it != lanes.end()) halting += as_double(it->second, libsumo::LAST_STEP_VEHICLE_HALTING_NUMBER);
        }
        // 7.5 m of lane per halted vehicle: halting count as occupancy of the approach.
        const double occupancy = a.length_m > 0.0 ? std::clamp(halting * 7.5 / a.length_m, 0.0, 1.0) : 0.0;
        engine.record_measurement(a.node, a.side, occupancy, std::nullopt);
      }
    }

    if (config.with_ev && !ev_added && t >= config.ev_depart_s) {
      dstar.emplace(cost, starts, goals);
      dstar->replan();
      const planner::Route r = dstar->route();
      if (!r.found) throw SimError("the EV's goal cannot be reached from its start");
      route = r.edges;
      libtraci::Route::add("ev_route", sumo_ids(sg, route));
      libtraci::Vehicle::add(kEv, "ev_route", config.signals == EvSignals::bluelight ? "ev_bluelight" : "ev", "now",
                             "best", "base", "max");
      libtraci::Vehicle::subscribe(kEv, {libsumo::VAR_ROAD_ID, libsumo::VAR_LANEPOSITION, libsumo::VAR_SPEED});
      ev_added = true;
      ev_depart = t;
      changed.clear();  // the new planner already knows every update so far
    }
    for (Incident& inc : incidents) {
      if (!inc.applied && t >= inc.time_s) {
        libtraci::Edge::setMaxSpeed(inc.edge, config.incident_speed_mps);
        inc.applied = true;
        spdlog::debug("event=incident t={:.0f} edge={}", t, inc.edge);
      }
    }

    if (ev_added && !ev_done) {
      const auto ev = libtraci::Vehicle::getSubscriptionResults(kEv);
      if (ev.empty()) {
        if (ev_seen) {
          ev_done = true;
          result.ev_arrived = true;
          result.ev_travel_time_s = t - ev_depart;
          if (config.signals == EvSignals::corridor) engine.cancel(kMission, t);
        }
      } else {
        ev_seen = true;
        const std::string road = as_string(ev, libsumo::VAR_ROAD_ID);
        if (as_double(ev, libsumo::VAR_SPEED) < 0.1) {
          std::string light;
          if (!road.empty() && road[0] != ':' && sg.stop_line.contains(road)) {
            const NodeId head = sg.stop_line.at(road);
            if (const auto it = scenario.sumo_plan_of.find(head); it != scenario.sumo_plan_of.end()) {
              light = fmt::format("node={} tls={} state={} mode={}", head.v, it->second->tls_id,
                                  libtraci::TrafficLight::getRedYellowGreenState(it->second->tls_id),
                                  controller.mode(head) == preemption::SignalMode::held ? "held" : "program");
            }
          }
          const auto leader = libtraci::Vehicle::getLeader(kEv, 50.0);
          const auto tls = libtraci::Vehicle::getNextTLS(kEv);
          spdlog::debug("event=ev_halted t={:.0f} road={} pos={:.1f} lane={} {} leader={}@{:.1f} next_tls={}:{} route={}", t, road,
                        as_double(ev, libsumo::VAR_LANEPOSITION), libtraci::Vehicle::getLaneID(kEv), light, leader.first,
                        leader.second, tls.empty() ? "" : tls.front().id, tls.empty() ? ' ' : tls.front().state,
                        fmt::join(libtraci::Vehicle::getRoute(kEv), ","));
        }
        if (!road.empty() && road[0] != ':' && !sg.arcs(road).empty()) {
          if (road != ev_edge && config.signals == EvSignals::corridor) {
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
              libtraci::Vehicle::setRoute(kEv, sumo_ids(sg, plan.edges));
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
        if (config.signals == EvSignals::corridor && plan.found) {
          const auto crossings = preemption::signalized_crossings(plan, scenario.plans, t);
          engine.update_route(kMission, 1, crossings, t);
        }
      }
    }
    if (config.signals == EvSignals::corridor) {
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
    if (ev_finished && lights_home && step % 10 == 0 && libtraci::Simulation::getMinExpectedNumber() == 0) break;
  }
  result.end_time_s = t;
  result.preempted_signals = preempted.size();
  result.lights_taken_over = controller.lights_taken_over();
  result.lights_back_on_program = controller.lights_on_program();
  result.safety_violations = controller.violations();
  bridge.close();

  double loss = 0.0;
  for (const TripInfo& trip : read_tripinfo(launch.tripinfo)) {
    if (trip.id == kEv) {
      if (trip.arrival_s >= 0.0) result.ev_travel_time_s = trip.duration_s;
      result.ev_stops = trip.waiting_count;
      result.ev_wait_s = trip.waiting_time_s;
      result.ev_time_loss_s = trip.time_loss_s;
      continue;
    }
    loss += trip.time_loss_s;
    ++result.others;
  }
  result.others_mean_time_loss_s = result.others > 0 ? loss / static_cast<double>(result.others) : 0.0;
  return result;
}

}  // namespace corridor::sim
