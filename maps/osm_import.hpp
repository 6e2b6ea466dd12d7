// Reads .osm, .osm.gz, .osm.bz2 and .osm.pbf files with libosmium into a RoadGraph for emergency
// vehicles: drivable ways, degree-2 chains compressed into edges, signalized intersections and
// barriers marked.
#pragma once

#include <filesystem>

#include "maps/graph_builder.hpp"
#include "maps/road_graph.hpp"

namespace corridor::maps {

struct OsmImportOptions {
  // A highway=traffic_signals node on a way (not at its junction) marks the nearest junction along
  // that way as signalized, if it lies within this distance.
  double signal_to_junction_max_m = 40.0;
  // Traffic keeps left (UK, Ireland, Japan, India, Australia...): a right turn crosses oncoming
  // traffic. OSM extracts rarely carry the country's driving_side, so the user says it.
  bool left_hand_traffic = false;
  bool show_progress = true;
};

struct OsmImportReport {
  std::size_t osm_ways_read = 0;
  std::size_t osm_ways_kept = 0;
  std::size_t osm_signal_nodes = 0;
  std::size_t osm_barrier_nodes = 0;  // nodes an emergency vehicle cannot pass (split into dead ends)
  std::size_t osm_stop_nodes = 0;     // barriers it passes but stops at (gates, toll booths), charged by the profile
  std::size_t osm_restrictions_applied = 0;     // restriction keys resolved onto graph edges
  std::size_t osm_restrictions_unresolved = 0;  // malformed, or members outside the graph
  GraphBuildReport graph;
};

// Throws MapLoadError with the file name and the cause for a missing, unreadable or corrupt file.
RoadGraph import_osm(const std::filesystem::path& file, const OsmImportOptions& options = {},
                     OsmImportReport* report = nullptr);

}  // namespace corridor::maps
