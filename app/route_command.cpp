#include "app/route_command.hpp"

#include <spdlog/spdlog.h>

#include <charconv>
#include <iostream>
#include <memory>
#include <optional>

#include "app/cli_error.hpp"
#include "app/map_options.hpp"
#include "maps/edge_snapper.hpp"
#include "maps/errors.hpp"
#include "maps/intersection_geometry.hpp"
#include "planner/dstar_lite.hpp"
#include "planner/one_to_one_search.hpp"
#include "planner/route_geojson.hpp"
#include "planner/snap_points.hpp"
#include "preemption/signal_costs.hpp"

namespace corridor::app {
namespace {

struct RouteOptions {
  MapOptions map;
  std::string from;
  std::string to;
  std::optional<double> vmax_kmh;  // the profile's when not given
  std::string algo = "dstar";
  double signal_delay_s = 0.0;
  std::string signals = "flat";
  double max_snap_m = 200.0;
  std::string profile = "ambulance";
};

maps::LatLon parse_lat_lon(const std::string& text, const char* option) {
  const auto comma = text.find(',');
  auto fail = [&] {
    return UsageError(std::string(option) + " expects LAT,LON in decimal degrees (for example 43.7384,7.4246), got '" +
                      text + "'");
  };
  if (comma == std::string::npos) throw fail();
  maps::LatLon p;
  const char* b = text.data();
  const char* e = text.data() + text.size();
  auto r1 = std::from_chars(b, b + comma, p.lat_deg);
  auto r2 = std::from_chars(b + comma + 1, e, p.lon_deg);
  if (r1.ec != std::errc{} || r1.ptr != b + comma || r2.ec != std::errc{} || r2.ptr != e) throw fail();
  if (!maps::is_valid_lat_lon(p)) {
    throw UsageError(std::string(option) + " is not a valid coordinate: latitude must be in [-90, 90] and longitude in [-180, 180]");
  }
  return p;
}

void run_route(const RouteOptions& o) {
  planner::Algorithm algo;
  if (o.algo == "dstar") {
    algo = planner::Algorithm::dstar_lite;
  } else if (o.algo == "astar") {
    algo = planner::Algorithm::astar;
  } else if (o.algo == "dijkstra") {
    algo = planner::Algorithm::dijkstra;
  } else {
    throw UsageError("--algo must be dstar, astar or dijkstra, got '" + o.algo + "'");
  }
  if (o.vmax_kmh && !(*o.vmax_kmh > 0.0 && *o.vmax_kmh <= 400.0)) throw UsageError("--vmax-kmh must be in (0, 400]");
  if (!(o.signal_delay_s >= 0.0 && o.signal_delay_s < 3600.0)) throw UsageError("--signal-delay-s must be in [0, 3600)");
  if (!(o.max_snap_m > 0.0 && o.max_snap_m <= 100000.0)) throw UsageError("--max-snap-m must be in (0, 100000] metres");
  if (o.signals != "flat" && o.signals != "preempted" && o.signals != "normal") {
    throw UsageError("--signals must be flat, preempted or normal, got '" + o.signals + "'");
  }
  const maps::LatLon from = parse_lat_lon(o.from, "--from");
  const maps::LatLon to = parse_lat_lon(o.to, "--to");

  const maps::RoadGraph graph = load_map_from_options(o.map);
  const maps::EdgeSnapper snapper(graph);
  maps::SnapOptions snap{o.max_snap_m};
  snap.skip_ferries = true;
  auto snap_or_explain = [&](maps::LatLon p, const char* which) {
    try {
      return snapper.snap(p, snap);
    } catch (const maps::SnapError& e) {
      throw maps::SnapError(e.reason(), std::string(which) + ": " + e.what());
    }
  };
  maps::SnapResult s = snap_or_explain(from, "--from");
  maps::SnapResult t = snap_or_explain(to, "--to");

  planner::CostOverlay overlay(graph);
  overlay.set_signal_delay(graph, o.signal_delay_s);
  if (o.signals != "flat") {
    // Each movement through a signal waits by its green share in the intersection's normal program
    // (a SUMO net's own plans, else the default NEMA plan from its legs), as the server charges it.
    preemption::set_signal_costs(overlay, graph, maps::signal_plans_for(o.map.map_file, graph).plans,
                                 o.signals == "preempted" ? preemption::SignalCostRule::preempted
                                                          : preemption::SignalCostRule::normal);
  }
  planner::VehicleProfile profile = planner::profile_by_name_or_file(o.profile);
  if (o.vmax_kmh) profile.vmax_mps = *o.vmax_kmh / 3.6;
  const planner::TravelCost cost(graph, overlay, profile);
  planner::Route route;
  planner::plan_nearest_or_main(snapper, graph, from, s, to, t, snap, [&](const maps::SnapResult& a, const maps::SnapResult& b) {
    const auto starts = planner::points_from_snap(graph, a, planner::PointRole::start);
    const auto goals = planner::at_same_node(graph, a, b) ? starts : planner::points_from_snap(graph, b, planner::PointRole::goal);
    if (algo == planner::Algorithm::dstar_lite) {
      planner::DStarLite dstar(cost, starts, goals);
      dstar.replan();
      route = dstar.route();
    } else {
      planner::OneToOneSearch search;
      route = search.run(planner::SearchSpace(cost, starts, goals), algo == planner::Algorithm::astar);
    }
    return route.found;
  });
  if (!route.found) throw std::runtime_error("no route: the destination cannot be reached from the start");
  auto feature = planner::route_to_geojson(graph, route, planner::to_string(algo));
  feature["properties"]["snap_distance_m"] = {s.distance_m, t.distance_m};
  feature["properties"]["profile"] = profile.name;
  feature["properties"]["signal_costs"] = o.signals;
  std::cout << feature.dump() << '\n';
}

}  // namespace

void register_route_command(CLI::App& app) {
  auto options = std::make_shared<RouteOptions>();
  auto* cmd = app.add_subcommand("route", "Plan one route and print it as a GeoJSON Feature");
  add_map_options(*cmd, options->map);
  cmd->add_option("--from", options->from, "start as LAT,LON")->required();
  cmd->add_option("--to", options->to, "destination as LAT,LON")->required();
  cmd->add_option("--vmax-kmh", options->vmax_kmh, "vehicle maximum speed in km/h (default: the profile's)");
  cmd->add_option("--profile", options->profile, "vehicle profile: ambulance, fire_engine, or a profile JSON file")
      ->capture_default_str();
  cmd->add_option("--algo", options->algo, "dstar, astar or dijkstra")->capture_default_str();
  cmd->add_option("--signal-delay-s", options->signal_delay_s, "expected delay at each signalized intersection")
      ->capture_default_str();
  cmd->add_option("--signals", options->signals,
                  "signal costs: flat (--signal-delay-s per intersection), preempted (each movement's expected "
                  "transition to its green) or normal (each movement's expected red in the normal program)")
      ->capture_default_str();
  cmd->add_option("--max-snap-m", options->max_snap_m, "farthest a coordinate may be from a road")->capture_default_str();
  cmd->callback([options] { run_route(*options); });
}

}  // namespace corridor::app
