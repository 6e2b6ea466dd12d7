#include "app/map_command.hpp"

#include <algorithm>
#include <chrono>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>

#include "app/map_options.hpp"
#include "maps/graph_cache.hpp"
#include "maps/osm_import.hpp"

namespace corridor::app {
namespace {

nlohmann::json describe(const maps::RoadGraph& g) {
  std::size_t signals = 0;
  for (NodeId v : g.nodes()) signals += g.signalized(v) ? 1 : 0;
  std::size_t stops = 0;  // nodes with a gate or toll booth the vehicle stops at
  for (NodeId v : g.nodes()) stops += g.stop_at(v) ? 1 : 0;
  const maps::LatLon lo = g.projection().to_lat_lon(g.min_corner());
  const maps::LatLon hi = g.projection().to_lat_lon(g.max_corner());
  return {{"nodes", g.node_count()},
          {"edges", g.edge_count()},
          {"signalized_nodes", signals},
          {"bbox", {lo.lon_deg, lo.lat_deg, hi.lon_deg, hi.lat_deg}},
          {"turn_restrictions", g.data().restrictions.size()},
          {"turns", g.turns().arc_count()},
          {"restriction_copies", g.turns().copy_count()},
          {"limited_edges", g.edge_limits().size()},
          {"stop_nodes", stops},
          {"main_component_nodes", g.main_component_nodes()},
          {"traffic_keeps", g.left_hand_traffic() ? "left" : "right"}};
}

struct ImportOptions {
  std::string input;
  std::string output;
  bool left_hand_traffic = false;
};

void run_import(const ImportOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  maps::OsmImportReport report;
  maps::OsmImportOptions import;
  import.left_hand_traffic = o.left_hand_traffic;
  const maps::RoadGraph graph = maps::import_osm(o.input, import, &report);
  const double import_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  maps::write_graph_cache(o.output, graph, maps::describe_source(o.input));
  const auto t1 = std::chrono::steady_clock::now();
  const maps::RoadGraph reloaded = maps::read_graph_cache(o.output);
  const double load_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
  auto j = describe(graph);
  j["input"] = o.input;
  j["output"] = o.output;
  j["import_seconds"] = import_s;
  j["cache_load_seconds"] = load_s;
  j["osm_ways_read"] = report.osm_ways_read;
  j["osm_ways_kept"] = report.osm_ways_kept;
  j["osm_signal_nodes"] = report.osm_signal_nodes;
  j["osm_barrier_nodes"] = report.osm_barrier_nodes;
  j["osm_stop_nodes"] = report.osm_stop_nodes;
  j["osm_restrictions_applied"] = report.osm_restrictions_applied;
  j["osm_restrictions_unresolved"] = report.osm_restrictions_unresolved;
  j["graph_nodes_before_scc"] = report.graph.input_nodes;
  // Kept since other tools read it; every road is kept now, so it counts nodes on no drivable road.
  j["dropped_nodes_outside_largest_scc"] = report.graph.dropped_nodes;
  j["dropped_nodes"] = report.graph.dropped_nodes;
  j["strongly_connected_components"] = report.graph.components;
  std::cout << j.dump(2) << '\n';
}

void run_info(const MapOptions& o) {
  maps::MapLoadInfo info;
  const maps::RoadGraph graph = load_map_from_options(o, &info);
  auto j = describe(graph);
  j["loaded_from"] = info.origin == maps::MapLoadInfo::Origin::cache ? "cache" : "import";
  j["cache_file"] = info.cache_file.string();
  j["load_seconds"] = info.seconds;
  if (info.origin == maps::MapLoadInfo::Origin::imported) {
    j["dropped_nodes_outside_largest_scc"] = info.import.graph.dropped_nodes;
    j["dropped_nodes"] = info.import.graph.dropped_nodes;
  }
  std::cout << j.dump(2) << '\n';
}

}  // namespace

void register_map_command(CLI::App& app) {
  auto* map = app.add_subcommand("map", "Import maps into graph caches and describe them");
  map->require_subcommand(1);

  auto import_options = std::make_shared<ImportOptions>();
  auto* import_cmd = map->add_subcommand("import", "Import an OSM file and write a graph cache");
  import_cmd->add_option("--input", import_options->input, "OSM file (.osm, .osm.gz, .osm.bz2, .osm.pbf)")->required();
  import_cmd->add_option("--out", import_options->output, "graph cache to write")->required();
  import_cmd->add_flag("--left-hand-traffic", import_options->left_hand_traffic,
                       "traffic keeps left (a right turn crosses oncoming traffic)");
  import_cmd->callback([import_options] { run_import(*import_options); });

  auto info_options = std::make_shared<MapOptions>();
  auto* info_cmd = map->add_subcommand("info", "Load a map (through the cache) and print its size and load time");
  add_map_options(*info_cmd, *info_options);
  info_cmd->callback([info_options] { run_info(*info_options); });
}

}  // namespace corridor::app
