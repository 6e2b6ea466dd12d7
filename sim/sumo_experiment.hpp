// `corridor experiment sumo`: the closed-loop matrix {static, dynamic} routing x {none, bluelight,
// corridor} signals over background volumes and seeds, each against a run without the EV, written
// as CSV, a median/IQR summary and plots. Runs go two at a time, each SUMO in its own process.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "sim/closed_loop.hpp"

namespace corridor::sim {

struct SumoExperimentOptions {
  std::string scenario = "grid";  // grid, a .net.xml, or an OSM file
  std::vector<double> volumes{200, 400, 600, 800};
  std::uint32_t seeds = 10;
  std::uint64_t first_seed = 1;
  std::filesystem::path out_dir;
  double demand_end_s = 900.0;
  double ev_depart_s = 300.0;
  double end_s = 2400.0;
  double congestion_period_s = 10.0;
  std::uint32_t incidents = 2;
  unsigned parallel = 2;
  SumoBackend backend = SumoBackend::traci;
};

struct ExperimentRow {
  EvRouting routing;
  EvSignals signals;
  double volume;
  std::uint64_t seed;
  ClosedLoopResult result;
  double baseline_time_loss_s;
  [[nodiscard]] double others_delay_rel() const;
};

// Runs the matrix and writes sumo_runs.csv, sumo_summary.csv, sumo_summary.md and the plots into
// out_dir. Returns the rows, sorted by volume, seed, routing and signals.
std::vector<ExperimentRow> run_sumo_experiment(const SumoExperimentOptions& options);

}  // namespace corridor::sim
