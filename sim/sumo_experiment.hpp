// `corridor experiment sumo`: the closed-loop matrix {static, dynamic} routing x {none, bluelight,
// corridor, corridor+bluelight} signals over demand levels and seeds, each against a run without
// the EV, written as CSV, a median/IQR summary and plots.
//
// A matrix is planned once, then either run here (two at a time, each SUMO run in a forked child),
// or emitted as one self-contained `corridor sim` command line per run for an existing engine (GNU
// parallel, over SSH hosts, a Slurm array) and collected afterwards. Every run leaves the same
// record file (`*.run.json`), a failed one too, and the plan itself is kept beside them
// (`runs/matrix.json`), so that a run whose process died is still a row. The outputs are always
// made from those records, so both ways give the same tables.
#pragma once

#include <nlohmann/json.hpp>

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "sim/closed_loop.hpp"
#include "sim/experiment_tables.hpp"
#include "sim/run_record.hpp"

namespace corridor::sim {

struct SumoExperimentOptions {
  std::string scenario = "grid";  // grid, a user's .sumocfg, a .net.xml, or an OSM file
  std::vector<double> volumes{200, 400, 600, 800};  // generated background traffic (veh/h)
  std::vector<double> demand_scales{1.0};           // a .sumocfg's own demand, times SUMO's --scale
  std::vector<EvRouting> routings{EvRouting::static_route, EvRouting::dynamic_route};
  std::vector<EvSignals> signals{EvSignals::none, EvSignals::bluelight, EvSignals::corridor,
                                 EvSignals::corridor_bluelight};
  std::uint32_t seeds = 10;
  std::uint64_t first_seed = 1;
  std::filesystem::path out_dir;
  double demand_end_s = 900.0;
  double ev_depart_s = 300.0;  // after the scenario's begin
  // After the scenario's begin; unset: a .sumocfg's own end, else 2400 s.
  std::optional<double> end_s;
  double congestion_period_s = 10.0;
  std::uint32_t incidents = 2;
  unsigned parallel = 2;
  SumoBackend backend = SumoBackend::traci;
  bool vicinity = true;   // false: the seed's route-only preemption (--route-only)
  // The seed's Fig. 11 protocol (--inject-on-route): `volumes` are injected along each EV's static
  // route, over background traffic of background_vph.
  bool inject_on_route = false;
  double background_vph = 400.0;
  std::uint32_t evs = 1;  // EVs per run (--evs): the further ones conflict with the first at its lights
  std::string ev_vclass = "emergency";  // the EV's SUMO vehicle class (--ev-vclass)
  bool rebuild_net = false;             // convert a net newer than the installed SUMO (--rebuild-net)
};

// Runs the matrix here and writes sumo_runs.csv, sumo_summary.csv, sumo_summary.md and the plots
// into out_dir. Returns the rows, sorted by demand, seed, routing and signals, and the runs that
// failed.
ExperimentTables run_sumo_experiment(const SumoExperimentOptions& options);

// Plans the matrix (nets and generated demand are built now, so that runs write only their own
// directories) and writes one `corridor sim` command line per run to `jobs_file`. Paths are
// absolute: run the lines on hosts that see the same paths. Returns the number of lines.
std::size_t emit_sumo_jobs(const SumoExperimentOptions& options, const std::filesystem::path& jobs_file,
                           const std::filesystem::path& corridor_binary);

// Reads every *.run.json under `dirs`, and every run a matrix.json there planned (one without a
// record is a failed row), and writes the CSVs, the summary and the plots into out_dir. Throws
// SimError when there is no record at all, or when records disagree on their scenario.
ExperimentTables collect_sumo_experiment(const std::vector<std::filesystem::path>& dirs, const std::filesystem::path& out_dir);

// The same from a list of record files; a file that is missing or is not a record is listed in the
// summary as a failed run.
ExperimentTables collect_run_files(std::vector<std::filesystem::path> files, const std::filesystem::path& out_dir);

}  // namespace corridor::sim
