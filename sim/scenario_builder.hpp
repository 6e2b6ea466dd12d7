// Builds SUMO scenarios: a network from OSM (netconvert) or a Manhattan grid (netgenerate), and
// seeded background demand (randomTrips.py + duarouter). Every file lands in one directory.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

#include "sim/sumo_config.hpp"

namespace corridor::sim {

struct GridSpec {
  int blocks = 5;           // junctions per side
  double block_m = 200.0;   // street length between junctions
  int lanes = 2;            // per direction
  double speed_kmh = 50.0;
};

struct ScenarioNet {
  std::string name;  // "grid", or the OSM file's or configuration's stem
  std::filesystem::path dir;
  std::filesystem::path net;
  // A user's scenario (.sumocfg): its own demand is the background traffic, and each run's SUMO
  // configuration is derived from it.
  std::optional<SumoConfig> config;
  // The user's net, when `net` is its conversion by the installed netconvert (NetOptions).
  std::filesystem::path rebuilt_from;
};

struct NetOptions {
  // A net written by a newer netconvert than the installed SUMO's is converted with the installed
  // netconvert into the scenario directory (the user's file is left as it is); without this it is
  // refused, since SUMO reads such a net without a word and misreads what changed.
  bool rebuild_net = false;
};

// A grid like the seed paper's: two lanes per direction, a traffic light at every junction.
ScenarioNet build_grid_net(const std::filesystem::path& dir, const GridSpec& spec);

// The seed's VISSIM grid (its Fig. 11): the same grid, but every light runs the seed's Fig. 3 NEMA
// dual-ring 8-phase program (maps::make_nema_plan: protected lefts, 3 s yellow, 2 s all-red),
// written as SUMO programs that replace netgenerate's (same program id) in a net compiled by
// netconvert. Scenario name "nema-grid".
ScenarioNet build_nema_grid_net(const std::filesystem::path& dir, const GridSpec& spec);

// netconvert with the options of the issue (signals guessed and joined, passenger roads only).
// A .pbf is first converted to .osm with osmium-tool, since netconvert does not read PBF.
ScenarioNet build_osm_net(const std::filesystem::path& dir, const std::filesystem::path& osm_file);

// "grid" (the default grid), "nema-grid" (the same with NEMA programs), a user's SUMO configuration
// (.sumocfg), a SUMO .net.xml used as it is, or an OSM file (.osm, .osm.gz, .pbf). A
// configuration's or net's files are read where they are and never written; `dir` receives what
// runs produce. Throws SimError for a missing or unusable file, and for a net newer than the
// installed SUMO unless options.rebuild_net.
ScenarioNet build_scenario_net(const std::string& scenario, const std::filesystem::path& dir, const NetOptions& options = {});

struct DemandSpec {
  double vehicles_per_hour = 400.0;
  double end_s = 900.0;  // insert background traffic until then
  std::uint64_t seed = 1;
};

// Background traffic routes (.rou.xml) from randomTrips.py, run with /usr/bin/python3 because
// SUMO's tools need Debian's Python modules. Reuses an existing file for the same spec.
std::filesystem::path build_background_demand(const ScenarioNet& net, const DemandSpec& spec);

}  // namespace corridor::sim
