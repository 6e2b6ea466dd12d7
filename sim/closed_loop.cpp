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

void write_ev_types(const std::filesystem::path& file, double vmax_mps) {
  std::ofstream out(file, std::ios::trunc);
  // The EV drives at the speed limit (speedFactor 1), like the planner's cost model, up to vmax.
  // The bluelight type may pass red lights slowly, as SUMO users configure it. With Corridor's
  // preemption as well (corridor+bluelight) the EV keeps the device (others make way) without the
  // red-running junction parameters, since the preemption is there to turn the red green. SUMO's
  // device still lets it pass a red by design, and SUMO's other drivers do not yield to it there.
  out << fmt::format(
      "<additional>\n"
      "  <vType id=\"ev\" vClass=\"emergency\" guiShape=\"emergency\" color=\"1,0,0\" maxSpeed=\"{0:.3f}\" "
      "speedFactor=\"1\" speedDev=\"0\"/>\n"
      "  <vType id=\"ev_bluelight\" vClass=\"emergency\" guiShape=\"emergency\" color=\"0,0,1\" maxSpeed=\"{0:.3f}\" "
      "speedFactor=\"1\" speedDev=\"0\" jmDriveAfterRedTime=\"300\" jmDriveRedSpeed=\"5.56\">\n"
      "    <param key=\"has.bluelight.device\" value=\"true\"/>\n"
      "  </vType>\n"
      "  <vType id=\"ev_bluelight_preempted\" vClass=\"emergency\" guiShape=\"emergency\" color=\"1,0,1\" "
      "maxSpeed=\"{0:.3f}\" speedFactor=\"1\" speedDev=\"0\">\n"
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


std::vector<Approach> approaches_of(const SumoScenario& scenario) {
  const auto& sg = scenario.graph;
  const auto& g = sg.graph;
  std::vector<Approach> approaches;
  for (const auto& [node, plan] : scenario.plans) {
    // A plan node is one approach's stop line.
    if (g.in_edges(node).empty()) continue;
    const maps::SumoEdge* se = scenario.net.edge(sg.sumo_edge_of_node[node.index()]);
    if (se == nullptr) continue;
    Approach a{node, maps::approach_side(g, g.in_edges(node).front()), {}, 0.0, {}, 0.0, 0.0, 0.0};
    for (const auto& lane : se->lanes) {
      a.lanes.push_back(lane.id);
      a.length_m += lane.length_m;
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
  if (!config.background_routes.empty()) launch.routes.push_back(config.background_routes);
  std::error_code ec;
  if (scenario.config) {
    launch.config = scenario.config->file;
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
    for (const auto& [option, value] : scenario.config->outputs) {
      if (option == "tripinfo-output") continue;  // the run's own, below
      launch.options.emplace_back(option, (config.out_dir / (config.run_name + "." + std::filesystem::path(value).filename().string())).string());
    }
  }
  const auto types = config.out_dir / (config.run_name + ".ev_types.add.xml");
  write_ev_types(types, config.ev_vmax_kmh / 3.6);
  launch.additional.push_back(types);
  launch.tripinfo = config.out_dir / (config.run_name + ".tripinfo.xml");
  launch.log = config.out_dir / (config.run_name + ".sumo.log");
  launch.end_s = config.end_s;
  launch.seed = config.seed;
  std::filesystem::remove(launch.tripinfo, ec);
  std::filesystem::remove(launch.log, ec);
  return launch;
}

void add_trip_results(const std::filesystem::path& tripinfo, ClosedLoopResult& result) {
  double loss = 0.0;
  for (const TripInfo& trip : read_tripinfo(tripinfo)) {
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
}

void count_lane_vehicles(const libsumo::SubscriptionResults& lanes, std::vector<Approach>& approaches) {
  for (Approach& a : approaches) {
    std::set<std::string> now;
    double halting = 0.0;
    for (const auto& lane : a.lanes) {
      const auto it = lanes.find(lane);
      if (it == lanes.end()) continue;
      halting += as_double(it->second, libsumo::LAST_STEP_VEHICLE_HALTING_NUMBER);
      if (const auto ids = it->second.find(libsumo::LAST_STEP_VEHICLE_ID_LIST); ids != it->second.end()) {
        if (const auto list = std::dynamic_pointer_cast<libsumo::TraCIStringList>(ids->second)) {
          now.insert(list->value.begin(), list->value.end());
        }
      }
    }
    for (const auto& v : now) a.arrivals += a.vehicles.contains(v) ? 0.0 : 1.0;
    for (const auto& v : a.vehicles) a.departures += now.contains(v) ? 0.0 : 1.0;
    a.vehicles = std::move(now);
    a.halting = halting;
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

ClosedLoopResult run_closed_loop(const SumoScenario& scenario, const ClosedLoopConfig& config) {
  if (!config.server_url.empty()) return run_closed_loop_server(scenario, config);
  return config.backend == SumoBackend::libsumo ? run_closed_loop_libsumo(scenario, config)
                                                : run_closed_loop_traci(scenario, config);
}

}  // namespace corridor::sim
