// The tables of an experiment matrix, made from its run records: sumo_runs.csv (every run of the
// matrix, failed ones included, with its status), sumo_summary.csv and .md (median and IQR per
// cell with its n, cells with failures flagged, and the headline comparison over the seeds where
// every compared strategy completed) and the two plots.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "sim/run_record.hpp"

namespace corridor::sim {

struct ExperimentRow {
  RunRecord run;
  // The other vehicles' mean time loss in the same demand and seed without the EV; nullopt when
  // that run failed or is missing.
  std::optional<double> baseline_time_loss_s;
  [[nodiscard]] bool ok() const { return run.status == RunStatus::ok; }
  [[nodiscard]] double others_delay_rel() const;  // NaN without a baseline
  [[nodiscard]] double ev_time_s() const;  // travel time, or the time it was still driving
};

// A run the matrix planned: the file its record is written to, and who it is where that is known
// (a run whose process died leaves no file, and still is a row).
struct PlannedRecord {
  std::filesystem::path file;
  std::optional<RunRecord> identity;
};

struct ExperimentTables {
  std::vector<ExperimentRow> rows;  // every run with the EV, sorted by demand, seed, routing and signals
  // Every run that did not complete (the runs without the EV included), and records that could not
  // be read: one line each, saying which run and why.
  std::vector<std::string> failures;
};

// Reads the records and writes the tables into out_dir. Throws SimError when no record can be read
// at all, or when the records mix scenarios or kinds of runs.
ExperimentTables write_experiment_tables(std::vector<PlannedRecord> runs, const std::filesystem::path& out_dir);

}  // namespace corridor::sim
