// Reads SUMO's floating car data (fcd-output, with --fcd-output.geo: x is longitude, y latitude)
// into one ground-truth trajectory per vehicle, for the map-matching accuracy study.
#pragma once

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "maps/geo.hpp"

namespace corridor::localizer {

struct TruthSample {
  double time_s = 0;
  maps::LatLon position;
  double heading_deg = 0;  // SUMO's angle: clockwise from north
  double speed_mps = 0;
  std::string lane;  // SUMO's lane id ("<edge>_<index>", ":<junction>_…" inside a junction), if given
};

// Vehicle id -> its samples in time order. Only ids starting with `prefix` (all when empty).
// Throws TraceError (trace_io.hpp) for a file that is missing or not fcd XML.
std::map<std::string, std::vector<TruthSample>> read_fcd(const std::filesystem::path& file, const std::string& prefix = "");

}  // namespace corridor::localizer
