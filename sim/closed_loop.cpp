#include "sim/closed_loop.hpp"

#include <libsumo/TraCIDefs.h>
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
#include "preemption/signal_costs.hpp"
#include "sim/errors.hpp"
#include "sim/closed_loop_run.hpp"

namespace corridor::sim {
namespace detail {

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

void write_ev_types(const std::filesystem::path& file, double vmax_mps, const std::string& vclass) {
  std::ofstream out(file, std::ios::trunc);
  // The EV drives at the speed limit (speedFactor 1), like the planner's cost model, up to vmax.
  // The bluelight type may pass red lights slowly, as SUMO users configure it. With Corridor's
  // preemption as well (corridor+bluelight) the EV keeps the device (others make way) without the
  // red-running junction parameters, since the preemption is there to turn the red green. SUMO's
  // device still lets it pass a red by design, and SUMO's other drivers do not yield to it there.
  out << fmt::format(
      "<additional>\n"
      "  <vType id=\"ev\" vClass=\"{1}\" guiShape=\"emergency\" color=\"1,0,0\" maxSpeed=\"{0:.3f}\" "
      "speedFactor=\"1\" speedDev=\"0\"/>\n"
      "  <vType id=\"ev_bluelight\" vClass=\"{1}\" guiShape=\"emergency\" color=\"0,0,1\" maxSpeed=\"{0:.3f}\" "
      "speedFactor=\"1\" speedDev=\"0\" jmDriveAfterRedTime=\"300\" jmDriveRedSpeed=\"5.56\">\n"
      "    <param key=\"has.bluelight.device\" value=\"true\"/>\n"
      "  </vType>\n"
      "  <vType id=\"ev_bluelight_preempted\" vClass=\"{1}\" guiShape=\"emergency\" color=\"1,0,1\" "
      "maxSpeed=\"{0:.3f}\" speedFactor=\"1\" speedDev=\"0\">\n"
      "    <param key=\"has.bluelight.device\" value=\"true\"/>\n"
      "  </vType>\n"
      "</additional>\n",
      vmax_mps, vclass);
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


std::vector<Approach> approaches_of(const SumoScenario& scenario) {
  const auto& sg = scenario.graph;
  const auto& g = sg.graph;
  std::vector<Approach> approaches;
  for (const auto& [node, plan] : scenario.plans) {
    // A plan node is one approach's stop line.
    if (g.in_edges(node).empty()) continue;
    const maps::SumoEdge* se = scenario.net.edge(sg.sumo_edge_of_node[node.index()]);
    if (se == nullptr) continue;
    Approach a;
    a.node = node;
    a.side = maps::approach_side(g, g.in_edges(node).front());
    for (const auto& lane : se->lanes) {
      a.lanes.push_back(lane.id);
      a.length_m += lane.length_m;
      if (!scenario.config) continue;
      for (const auto& d : scenario.config->lane_area_detectors) {
        const bool covers = std::find(d.lanes.begin(), d.lanes.end(), lane.id) != d.lanes.end();
        if (covers && std::find(a.detectors.begin(), a.detectors.end(), d.id) == a.detectors.end()) a.detectors.push_back(d.id);
      }
      for (const auto& loop : scenario.config->induction_loops) {
        if (loop.lane != lane.id) continue;
        // SUMO reads a negative position from the lane's end.
        const double pos = loop.pos_m < 0.0 ? lane.length_m + loop.pos_m : loop.pos_m;
        a.loops.push_back({loop.id, std::clamp(lane.length_m - pos, 0.0, lane.length_m), {}});
      }
    }
    approaches.push_back(std::move(a));
  }
  // The same order in every run, whatever the hash map's.
  std::sort(approaches.begin(), approaches.end(), [](const Approach& x, const Approach& y) { return x.node < y.node; });
  return approaches;
}

SumoLaunch launch_for(const SumoScenario& scenario, const ClosedLoopConfig& config) {
  SumoLaunch launch;
  launch.net = scenario.net_file;
  launch.scale = config.demand_scale;
  std::error_code ec;
  if (scenario.config) {
    launch.user_options = scenario.config->options;
    launch.user_dir = scenario.config->file.parent_path();
    launch.routes = scenario.config->route_files;
    // The scenario's additional files are copied into the run directory, so that the outputs they
    // declare (detector files, relative to the additional file) land there and not beside the
    // user's files.
    const auto inputs = config.out_dir / (config.run_name + ".inputs");
    std::filesystem::create_directories(inputs, ec);
    for (const auto& file : scenario.config->additional_files) {
      const auto copy = inputs / file.filename();
      std::filesystem::copy_file(file, copy, std::filesystem::copy_options::overwrite_existing, ec);
      if (ec) throw SimError("cannot copy " + file.string() + " into " + inputs.string() + ": " + ec.message());
      launch.additional.push_back(copy);
    }
    // The configuration's own outputs go to the run directory, never beside the user's files.
    launch.redirect_output = [dir = config.out_dir, run = config.run_name](const std::string&, const std::string& value) {
      return (dir / (run + "." + std::filesystem::path(value).filename().string())).string();
    };
  }
  if (!config.background_routes.empty()) launch.routes.push_back(config.background_routes);
  if (config.inject_on_route_vph > 0.0) {
    const auto& g = scenario.graph.graph;
    const planner::CostOverlay free_flow(g);
    const planner::TravelCost cost(g, free_flow, {config.ev_vmax_kmh / 3.6});
    planner::OneToOneSearch search;
    const auto starts = points_on(scenario.graph, config.ev_from, 0.0);
    const auto goals = points_on(scenario.graph, config.ev_to, std::nullopt);
    if (starts.empty() || goals.empty()) throw SimError("traffic cannot be injected on the route of unknown edges");
    const planner::Route r = search.run(planner::SearchSpace(cost, starts, goals), true);
    if (!r.found) throw SimError("the EV's goal cannot be reached from its start");
    std::string edges;
    for (const auto& id : sumo_ids(scenario.graph, r.edges)) edges += (edges.empty() ? "" : " ") + id;
    const auto file = config.out_dir / (config.run_name + ".inject.rou.xml");
    std::ofstream out(file, std::ios::trunc);
    out << fmt::format(
        "<routes>\n  <route id=\"inject_route\" edges=\"{}\"/>\n"
        "  <flow id=\"inject\" route=\"inject_route\" begin=\"{:g}\" end=\"{:g}\" vehsPerHour=\"{:g}\" "
        "departLane=\"best\" departSpeed=\"max\"/>\n</routes>\n",
        edges, std::max(0.0, config.ev_depart_s - 600.0), config.end_s, config.inject_on_route_vph);
    if (!out) throw SimError("cannot write " + file.string());
    launch.routes.push_back(file);
  }
  const auto types = config.out_dir / (config.run_name + ".ev_types.add.xml");
  write_ev_types(types, config.ev_vmax_kmh / 3.6, scenario.ev_vclass);
  launch.additional.push_back(types);
  launch.tripinfo = config.out_dir / (config.run_name + ".tripinfo.xml");
  launch.log = config.out_dir / (config.run_name + ".sumo.log");
  launch.end_s = config.end_s;
  launch.seed = config.seed;
  launch.run_config = config.out_dir / (config.run_name + ".sumocfg");
  std::filesystem::remove(launch.tripinfo, ec);
  std::filesystem::remove(launch.log, ec);
  write_launch_config(launch, scenario.sumo_options);
  return launch;
}

void add_trip_results(const std::filesystem::path& tripinfo, const std::vector<std::string>& ev_ids, ClosedLoopResult& result) {
  double loss = 0.0;
  result.evs.assign(ev_ids.size(), EvOutcome{});
  for (std::size_t k = 0; k < ev_ids.size(); ++k) result.evs[k].id = ev_ids[k];
  for (const TripInfo& trip : read_tripinfo(tripinfo)) {
    const auto ev = std::find(ev_ids.begin(), ev_ids.end(), trip.id);
    if (ev != ev_ids.end()) {
      EvOutcome& o = result.evs[static_cast<std::size_t>(ev - ev_ids.begin())];
      o.arrived = trip.arrival_s >= 0.0;
      if (o.arrived) o.travel_time_s = trip.duration_s;
      o.stops = trip.waiting_count;
      o.wait_s = trip.waiting_time_s;
      o.time_loss_s = trip.time_loss_s;
      continue;
    }
    loss += trip.time_loss_s;
    ++result.others;
  }
  if (!result.evs.empty()) {
    const EvOutcome& first = result.evs.front();
    result.ev_arrived = result.ev_arrived || first.arrived;
    if (first.arrived) result.ev_travel_time_s = first.travel_time_s;
    result.ev_stops = first.stops;
    result.ev_wait_s = first.wait_s;
    result.ev_time_loss_s = first.time_loss_s;
  }
  result.others_mean_time_loss_s = result.others > 0 ? loss / static_cast<double>(result.others) : 0.0;
}

void count_lane_vehicles(const libsumo::SubscriptionResults& lanes, std::vector<Approach>& approaches) {
  for (Approach& a : approaches) {
    std::set<std::string> now;
    double halting = 0.0;
    a.queue_m = 0.0;
    for (const auto& lane : a.lanes) {
      const auto it = lanes.find(lane);
      if (it == lanes.end()) continue;
      const double lane_halting = as_double(it->second, libsumo::LAST_STEP_VEHICLE_HALTING_NUMBER);
      if (!std::isfinite(lane_halting)) continue;
      halting += lane_halting;
      // Halted vehicles queue from the stop line back: 7.5 m each, the occupancy's jam spacing.
      a.queue_m = std::max(a.queue_m, 7.5 * lane_halting);
      if (const auto ids = it->second.find(libsumo::LAST_STEP_VEHICLE_ID_LIST); ids != it->second.end()) {
        if (const auto list = std::dynamic_pointer_cast<libsumo::TraCIStringList>(ids->second)) {
          now.insert(list->value.begin(), list->value.end());
        }
      }
    }
    // Where the user's loops count, they are the approach's counts (count_loop_vehicles).
    if (!a.counts_arrivals_by_loop()) {
      for (const auto& v : now) a.arrivals += a.vehicles.contains(v) ? 0.0 : 1.0;
    }
    if (!a.counts_departures_by_loop()) {
      for (const auto& v : a.vehicles) a.departures += now.contains(v) ? 0.0 : 1.0;
    }
    a.vehicles = std::move(now);
    a.halting = halting;
  }
}

std::optional<LaneLink> link_of_lane(const SumoScenario& scenario, const std::string& lane, const std::string& next_edge) {
  if (lane.empty()) return std::nullopt;
  if (lane.front() == ':') {
    // A junction's internal lane ":J_k_n", or one further along the same internal edge: the
    // connection whose via lane is on that edge.
    const std::string edge = lane.substr(0, lane.rfind('_'));
    for (const maps::SumoConnection& c : scenario.net.connections) {
      if (!c.tl.empty() && c.via.rfind(edge + "_", 0) == 0) return LaneLink{c.tl, c.link_index};
    }
    return std::nullopt;
  }
  // Before the junction: the connection from this lane towards the vehicle's next edge.
  const auto underscore = lane.rfind('_');
  if (underscore == std::string::npos) return std::nullopt;
  const std::string from = lane.substr(0, underscore);
  const int from_lane = std::atoi(lane.c_str() + underscore + 1);
  for (const maps::SumoConnection& c : scenario.net.connections) {
    if (!c.tl.empty() && c.from == from && c.from_lane == from_lane && (next_edge.empty() || c.to == next_edge)) {
      return LaneLink{c.tl, c.link_index};
    }
  }
  return std::nullopt;
}

// A loop this close to the stop line is a stop-bar detector: what it sees leave has crossed.
constexpr double kStopBarLoopM = 15.0;

bool Approach::counts_departures_by_loop() const {
  return std::any_of(loops.begin(), loops.end(), [](const Loop& l) { return l.distance_m <= kStopBarLoopM; });
}

bool Approach::counts_arrivals_by_loop() const {
  return std::any_of(loops.begin(), loops.end(), [](const Loop& l) { return l.distance_m > kStopBarLoopM; });
}

double reported_occupancy(const Approach& a) { return a.loops.empty() ? a.occupancy() : a.loop_occupancy; }

void count_loop_vehicles(const libsumo::SubscriptionResults& loops, std::vector<Approach>& approaches) {
  for (Approach& a : approaches) {
    if (a.loops.empty()) continue;
    a.loop_occupancy = 0.0;
    a.loop_queue_m = 0.0;
    for (Approach::Loop& loop : a.loops) {
      const auto it = loops.find(loop.id);
      if (it == loops.end()) continue;
      std::set<std::string> now;
      if (const auto ids = it->second.find(libsumo::LAST_STEP_VEHICLE_ID_LIST); ids != it->second.end()) {
        if (const auto list = std::dynamic_pointer_cast<libsumo::TraCIStringList>(ids->second)) {
          now.insert(list->value.begin(), list->value.end());
        }
      }
      // A vehicle counts once, when it first reaches the loop.
      double fresh = 0.0;
      for (const auto& v : now) fresh += loop.vehicles.contains(v) ? 0.0 : 1.0;
      if (loop.distance_m <= kStopBarLoopM) {
        a.departures += fresh;
      } else {
        a.arrivals += fresh;
      }
      loop.vehicles = std::move(now);
      const double occupancy = as_double(it->second, libsumo::LAST_STEP_OCCUPANCY);  // percent of the step
      if (std::isfinite(occupancy)) a.loop_occupancy = std::max(a.loop_occupancy, std::clamp(occupancy / 100.0, 0.0, 1.0));
      // A vehicle standing on the loop: the queue reaches back at least to it, and one car beyond.
      const double speed = as_double(it->second, libsumo::LAST_STEP_MEAN_SPEED);
      if (!loop.vehicles.empty() && std::isfinite(speed) && speed >= 0.0 && speed < 1.0) {
        a.loop_queue_m = std::max(a.loop_queue_m, loop.distance_m + 7.5);
      }
    }
    // Loops see the queue only where they are; lane-area detectors, where there are some, see all of it.
    if (a.detectors.empty()) a.queue_m = a.loop_queue_m;
  }
}

void add_detector_queues(const libsumo::SubscriptionResults& detectors, std::vector<Approach>& approaches) {
  for (Approach& a : approaches) {
    if (a.detectors.empty()) continue;
    double jam = 0.0;
    bool any = false;
    for (const auto& id : a.detectors) {
      const auto it = detectors.find(id);
      if (it == detectors.end()) continue;
      const double m = as_double(it->second, libsumo::JAM_LENGTH_METERS);
      if (!std::isfinite(m) || m < 0.0) continue;
      jam = std::max(jam, m);
      any = true;
    }
    if (any) a.queue_m = jam;
  }
}

}  // namespace detail

const char* to_string(EvRouting r) { return r == EvRouting::static_route ? "static" : "dynamic"; }
const char* to_string(EvSignals s) {
  switch (s) {
    case EvSignals::none: return "none";
    case EvSignals::bluelight: return "bluelight";
    case EvSignals::corridor: return "corridor";
    case EvSignals::corridor_bluelight: return "corridor+bluelight";
  }
  return "?";
}

std::optional<EvRouting> parse_ev_routing(const std::string& text) {
  for (EvRouting r : {EvRouting::static_route, EvRouting::dynamic_route}) {
    if (text == to_string(r)) return r;
  }
  return std::nullopt;
}

std::optional<EvSignals> parse_ev_signals(const std::string& text) {
  for (EvSignals s : {EvSignals::none, EvSignals::bluelight, EvSignals::corridor, EvSignals::corridor_bluelight}) {
    if (text == to_string(s)) return s;
  }
  return std::nullopt;
}

std::pair<std::string, std::string> pick_ev_trip(const SumoScenario& scenario, std::uint64_t seed) {
  const auto& g = scenario.graph.graph;
  planner::Rng rng(planner::derive_seed(seed, "ev-trip/" + scenario.name));
  const double diagonal = maps::distance_m(g.min_corner(), g.max_corner());
  const planner::CostOverlay overlay(g);
  const planner::TravelCost cost(g, overlay, {});
  planner::OneToOneSearch search;
  const auto m = static_cast<std::uint32_t>(g.edge_count());
  std::set<std::string> all_lights;
  for (const auto& plan : scenario.sumo_plans) all_lights.insert(plan.tls_id);
  const std::size_t wanted_lights = std::min<std::size_t>(2, all_lights.size());
  for (int attempt = 0; attempt < 20000; ++attempt) {
    const EdgeId a{rng.below(m)};
    const EdgeId b{rng.below(m)};
    const double d = maps::distance_m(g.point_along(a, 0.0), g.point_along(b, g.length_m(b)));
    if (a == b || d < 0.5 * diagonal * (1.0 - attempt / 40000.0)) continue;
    const planner::SearchSpace space(cost, {{a, 0.0}}, {{b, g.length_m(b)}});
    const planner::Route r = search.run(space, true);
    // A trip that crosses at least two traffic lights, where the net has them: preemption is the point.
    std::set<std::string> lights;
    for (NodeId v : r.nodes) {
      if (const auto it = scenario.sumo_plan_of.find(v); it != scenario.sumo_plan_of.end()) lights.insert(it->second->tls_id);
    }
    if (r.found && r.edges.size() >= 4 && (lights.size() >= wanted_lights || attempt > 15000)) {
      return {scenario.graph.sumo_edge_of_arc[a.index()], scenario.graph.sumo_edge_of_arc[b.index()]};
    }
  }
  throw SimError("no connected start/goal pair for the emergency vehicle on " + scenario.name);
}

std::vector<EvTrip> conflicting_ev_trips(const SumoScenario& scenario, const EvTrip& first, std::size_t count,
                                         std::uint64_t seed, double ev_vmax_kmh) {
  std::vector<EvTrip> trips;
  if (count == 0) return trips;
  const auto& sg = scenario.graph;
  const auto& g = sg.graph;
  // The loop's own initial costs, so that the predicted meeting is the one the planners will see.
  planner::CostOverlay overlay(g);
  preemption::set_signal_costs(overlay, g, scenario.plans, preemption::SignalCostRule::preempted);
  const planner::TravelCost cost(g, overlay, {ev_vmax_kmh / 3.6});
  planner::OneToOneSearch search;
  const auto starts = detail::points_on(sg, first.from, 0.0);
  const auto goals = detail::points_on(sg, first.to, std::nullopt);
  if (starts.empty() || goals.empty()) throw SimError("the first EV's edges '" + first.from + "', '" + first.to + "' are not drivable");
  const planner::Route main = search.run(planner::SearchSpace(cost, starts, goals), true);
  if (!main.found) throw SimError("the first EV's goal '" + first.to + "' cannot be reached from '" + first.from + "'");
  // The first EV's lights, with its approach edge and predicted arrival there.
  struct Light {
    std::string tls;
    std::string approach;
    double arrival_s;
  };
  std::vector<Light> lights;
  // The lights it crosses: not the goal edge's own stop line, which it never reaches.
  for (std::size_t i = 0; i < main.nodes.size() && i + 1 < main.edges.size(); ++i) {
    const auto it = scenario.sumo_plan_of.find(main.nodes[i]);
    if (it != scenario.sumo_plan_of.end()) lights.push_back({it->second->tls_id, sg.sumo_edge_of_node[main.nodes[i].index()], first.depart_s + main.arrival_s[i]});
  }
  if (lights.empty()) throw SimError("the first EV's route crosses no traffic light, so no other EV can conflict with it");
  planner::Rng rng(planner::derive_seed(seed, "conflicting-evs/" + scenario.name));
  const auto m = static_cast<std::uint32_t>(g.edge_count());
  for (std::size_t k = 0; k < count; ++k) {
    // The k-th shares the first's (k mod n)-th light from the middle of its route outwards.
    const Light& light = lights[(lights.size() / 2 + k) % lights.size()];
    bool found = false;
    for (int attempt = 0; attempt < 50000 && !found; ++attempt) {
      const EdgeId a{rng.below(m)};
      const EdgeId b{rng.below(m)};
      if (a == b) continue;
      // Between SUMO edges, as the loop will plan it: from any way onto the start to any onto the goal.
      const planner::Route r = search.run(planner::SearchSpace(cost, detail::points_on(sg, sg.sumo_edge_of_arc[a.index()], 0.0),
                                                               detail::points_on(sg, sg.sumo_edge_of_arc[b.index()], std::nullopt)),
                                          true);
      if (!r.found || r.edges.size() < 4) continue;
      for (std::size_t i = 0; i < r.nodes.size() && i + 1 < r.edges.size(); ++i) {
        const auto it = scenario.sumo_plan_of.find(r.nodes[i]);
        if (it == scenario.sumo_plan_of.end() || it->second->tls_id != light.tls) continue;
        // Another approach into the same light, at least 20 s of driving before it.
        if (sg.sumo_edge_of_node[r.nodes[i].index()] == light.approach || r.arrival_s[i] < 20.0) break;
        const double depart = light.arrival_s - r.arrival_s[i];
        if (depart < 0.0) break;
        spdlog::debug("event=conflicting_ev tls={} first_arrival_s={:.1f} its_arrival_after_s={:.1f} depart_s={:.1f}", light.tls,
                     light.arrival_s, r.arrival_s[i], depart);
        trips.push_back({sg.sumo_edge_of_arc[a.index()], sg.sumo_edge_of_arc[b.index()], depart,
                         static_cast<int>(count - k)});
        found = true;
        break;
      }
    }
    if (!found) throw SimError("no trip crosses traffic light '" + light.tls + "' from another approach on " + scenario.name);
  }
  return trips;
}

ClosedLoopResult run_closed_loop(const SumoScenario& scenario, const ClosedLoopConfig& config) {
  if (!config.server_url.empty() && !config.more_evs.empty()) {
    throw SimError("several EVs (--evs) run in the in-process loop only, not through a server (--server)");
  }
  if (!config.server_url.empty()) return run_closed_loop_server(scenario, config);
  return config.backend == SumoBackend::libsumo ? run_closed_loop_libsumo(scenario, config)
                                                : run_closed_loop_traci(scenario, config);
}

}  // namespace corridor::sim
