// CLI options shared by every subcommand that loads a map: --map, --cache-dir, --no-cache,
// --left-hand-traffic.
#pragma once

#include <CLI/CLI.hpp>
#include <filesystem>
#include <string>

#include "maps/map_loader.hpp"

namespace corridor::app {

struct MapOptions {
  std::string map_file;  // empty = the embedded default map
  std::string cache_dir;
  bool no_cache = false;
  bool left_hand_traffic = false;
};

void add_map_options(CLI::App& cmd, MapOptions& options);

// Resolves defaults ($CORRIDOR_CACHE_DIR, $XDG_CACHE_HOME/corridor, ~/.cache/corridor) and loads.
maps::RoadGraph load_map_from_options(const MapOptions& options, maps::MapLoadInfo* info = nullptr);

}  // namespace corridor::app
