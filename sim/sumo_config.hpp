// A user's SUMO configuration (.sumocfg), read as SUMO reads it, so that Corridor can run inside
// the scenario unchanged: every element with a `value` attribute is an option whatever section
// holds it, file lists are separated by commas, and relative paths are relative to the
// configuration's own directory. Corridor reads the inputs and the time window; SUMO itself is
// started with -c on the user's file, and only the options a run must own are overridden.
#pragma once

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "sim/sumo_options.hpp"

namespace corridor::sim {

// A lane-area (e2) detector of the user's additional files: what SUMO's LaneArea API reads.
struct LaneAreaDetector {
  std::string id;
  std::vector<std::string> lanes;  // `lane`, or the chain of `lanes`
};

// An induction loop (e1) of the user's additional files: where it sits on its lane. SUMO reads a
// negative position from the lane's end.
struct InductionLoop {
  std::string id;
  std::string lane;
  double pos_m = 0.0;
};

struct SumoConfig {
  std::filesystem::path file;  // absolute
  // Every option the file sets, as it sets it (a synonym stays a synonym), in file order: a run's
  // own configuration is derived from these (sumo_options.hpp).
  std::vector<SumoOptionValue> options;
  std::filesystem::path net_file;
  std::vector<std::filesystem::path> route_files;
  std::vector<std::filesystem::path> additional_files;
  double begin_s = 0.0;
  std::optional<double> end_s;
  // Output options the file sets (tripinfo-output, summary-output, log, ...) and their values: a
  // run sends each to its own directory so that nothing is written beside the user's files.
  std::map<std::string, std::string> outputs;
  // The e2 detectors the additional files declare (laneAreaDetector or e2Detector): where present,
  // their jam lengths are the queue estimate of the approaches they cover.
  std::vector<LaneAreaDetector> lane_area_detectors;
  // The induction loops (inductionLoop or e1Detector): where present on an approach, their counts,
  // occupancy and stopped vehicles are what the approach's detectors report.
  std::vector<InductionLoop> induction_loops;
};

// Throws SimError, naming the file and the option, for a configuration that is missing, not XML,
// has no net-file, names a file that does not exist, or has a time that is not a number.
SumoConfig read_sumo_config(const std::filesystem::path& file);

// SUMO's time format: seconds ("25200", "25200.5") or "[[D:]H:]M:S" ("7:00:00"). nullopt otherwise.
std::optional<double> parse_sumo_time(const std::string& text);

// "1.15.0" from `<binary> --version`. Throws SimError when the binary does not run.
std::string installed_sumo_version(const std::string& binary = "sumo");

// Throws SimError when a net written by a newer netconvert (its <net version>) is given to an
// older SUMO: SUMO 1.15 loads such a net without a word and misreads what changed since.
void check_net_version(const std::filesystem::path& net_file, const std::string& net_version,
                       const std::string& sumo_version);

}  // namespace corridor::sim
