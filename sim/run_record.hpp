// One run of an experiment matrix as a record: its identity (scenario, strategy, demand, seed, the
// EV's trip) and its result, or why it failed. `corridor sim --result FILE` writes one, every run of
// `experiment sumo` leaves one, and the tables are made from them; a run that failed is a record
// too, so that it is a row of the tables and never vanishes from them.
#pragma once

#include <nlohmann/json.hpp>

#include <cstdint>
#include <filesystem>
#include <string>

#include "sim/closed_loop.hpp"

namespace corridor::sim {

enum class RunStatus { ok, failed };
const char* to_string(RunStatus s);  // "ok", "failed"

struct RunRecord {
  std::string scenario;
  bool with_ev = true;
  EvRouting routing = EvRouting::dynamic_route;
  EvSignals signals = EvSignals::corridor;
  // Generated background veh/h (0 for a scenario's own demand); with inject_on_route, the volume
  // injected on the EV's static route.
  double volume = 0.0;
  bool inject_on_route = false;
  double demand_scale = 1.0;  // SUMO's --scale
  std::uint64_t seed = 1;
  std::string ev_from;
  std::string ev_to;
  double ev_depart_s = 0.0;  // simulation time
  bool vicinity = true;      // vicinity-aware preemption, or route-only
  std::uint32_t evs = 1;
  RunStatus status = RunStatus::ok;
  std::string failure;  // why, when failed: SUMO's or Corridor's own message
  ClosedLoopResult result;
};

nlohmann::json to_json_record(const RunRecord& r);
// Throws SimError naming `source` for a record that is not one. A failed run's record (with its
// identity) reads as a RunRecord with status failed; a bare {"error": ...} without one throws.
RunRecord record_from_json(const nlohmann::json& j, const std::string& source);

// `identity` marked failed for `why`.
[[nodiscard]] RunRecord failed_run(RunRecord identity, std::string why);

// Writes the record whole under a temporary name, then renames it: a collector never reads half a
// record. Throws SimError when the file cannot be written.
void write_record(const std::filesystem::path& file, const RunRecord& r);

}  // namespace corridor::sim
