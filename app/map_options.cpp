#include "app/map_options.hpp"

#include <spdlog/spdlog.h>

#include <cstdlib>

namespace corridor::app {
namespace {

std::filesystem::path default_cache_dir() {
  if (const char* dir = std::getenv("CORRIDOR_CACHE_DIR"); dir != nullptr && *dir != '\0') return dir;
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg != nullptr && *xdg != '\0') {
    return std::filesystem::path(xdg) / "corridor";
  }
  if (const char* home = std::getenv("HOME"); home != nullptr && *home != '\0') {
    return std::filesystem::path(home) / ".cache" / "corridor";
  }
  return {};
}

}  // namespace

void add_map_options(CLI::App& cmd, MapOptions& options) {
  cmd.add_option("--map", options.map_file,
                 "OSM file (.osm, .osm.gz, .osm.bz2, .osm.pbf) or graph cache; default: the embedded Monaco map");
  cmd.add_option("--cache-dir", options.cache_dir, "where imported graphs are cached (default ~/.cache/corridor)");
  cmd.add_flag("--no-cache", options.no_cache, "import the map without reading or writing a cache");
  cmd.add_flag("--left-hand-traffic", options.left_hand_traffic,
               "traffic keeps left (UK, Japan, ...): a right turn crosses oncoming traffic");
}

maps::RoadGraph load_map_from_options(const MapOptions& options, maps::MapLoadInfo* info) {
  maps::MapLoadOptions load;
  load.import.left_hand_traffic = options.left_hand_traffic;
  if (!options.no_cache) {
    load.cache_dir = options.cache_dir.empty() ? default_cache_dir() : std::filesystem::path(options.cache_dir);
  }
  const std::filesystem::path file = options.map_file.empty() ? CORRIDOR_DEFAULT_MAP : options.map_file;
  maps::MapLoadInfo local;
  maps::RoadGraph graph = maps::load_map(file, load, &local);
  spdlog::info("event=map_loaded file={} origin={} nodes={} edges={} seconds={:.3f}", file.string(),
               local.origin == maps::MapLoadInfo::Origin::cache ? "cache" : "import", graph.node_count(),
               graph.edge_count(), local.seconds);
  if (info != nullptr) *info = local;
  return graph;
}

}  // namespace corridor::app
