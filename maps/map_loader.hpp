// Loads a road graph from an OSM file or a graph cache, reusing a cache that is newer than the source.
#pragma once

#include <filesystem>
#include <optional>
#include <unordered_map>

#include "maps/osm_import.hpp"
#include "maps/road_graph.hpp"
#include "maps/signal_map.hpp"
#include "maps/signal_plan.hpp"

namespace corridor::maps {

struct MapLoadOptions {
  // Where imported graphs are cached; no caching when empty.
  std::filesystem::path cache_dir;
  OsmImportOptions import;
};

struct MapLoadInfo {
  enum class Origin { imported, cache } origin = Origin::imported;
  std::filesystem::path cache_file;  // the cache read or written, if any
  double seconds = 0.0;
  OsmImportReport import;  // filled when imported
};

// `file` is an OSM file (.osm, .osm.gz, .osm.bz2, .osm.pbf), a SUMO network (.net.xml: the
// edge-based graph of maps/sumo_graph.hpp, in the net's own metric frame around lat/lon 0,0), or a
// graph cache written earlier.
RoadGraph load_map(const std::filesystem::path& file, const MapLoadOptions& options, MapLoadInfo* info = nullptr);

bool is_sumo_net(const std::filesystem::path& file);

// The signals of a map loaded by load_map: SUMO's traffic lights for a SUMO network (one signal per
// light over all its stop lines), NEMA plans at the OSM signals otherwise.
SignalMap signal_plans_for(const std::filesystem::path& file, const RoadGraph& graph);

// The cache file used for `source` inside `cache_dir`: one per absolute source path.
std::filesystem::path cache_file_for(const std::filesystem::path& source, const std::filesystem::path& cache_dir);

}  // namespace corridor::maps
