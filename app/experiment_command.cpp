#include "app/experiment_command.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <fstream>
#include <iostream>
#include <memory>

#include "app/cli_error.hpp"
#include "app/map_options.hpp"
#include "app/sim_command.hpp"
#include "planner/experiments/analytical_experiments.hpp"

namespace corridor::app {
namespace {

struct AnalyticalCommandOptions {
  std::vector<std::string> graphs;
  std::string out_dir;
  std::uint64_t seed = 1;
  std::uint32_t runs = 10;
  std::uint32_t level_runs = 100;
  std::uint32_t pairs = 1000;
  unsigned threads = 2;
  double vmax_kmh = 120.0;
  std::string map_signals = "junctions";
  MapOptions map;  // cache settings for OSM files
};

// "monaco.osm.gz" -> "monaco": the prefix of the output files.
std::string map_name(const std::filesystem::path& file) {
  std::string name = file.filename().string();
  name = name.substr(0, name.find('.'));
  return name.empty() ? "map" : name;
}

std::vector<planner::ExperimentReport> run_one(const std::string& graph, const planner::AnalyticalOptions& options,
                                               const MapOptions& map) {
  if (auto builtin = planner::builtin_analytical_graph(graph)) return planner::run_graph_experiments(*builtin, options);
  const std::filesystem::path file(graph);
  if (!std::filesystem::exists(file)) {
    throw UsageError("--graph must be simple, complex, a graph .json file or an OSM map file; '" + graph +
                     "' is none of these (no such file)");
  }
  if (file.extension() == ".json") return planner::run_graph_experiments(planner::load_analytical_graph(file), options);
  MapOptions m = map;
  m.map_file = graph;
  return planner::run_map_experiments(load_map_from_options(m), map_name(file), options);
}

void run_analytical(const AnalyticalCommandOptions& o) {
  if (o.runs == 0 || o.level_runs == 0 || o.pairs == 0) throw UsageError("--runs, --level-runs and --pairs must be at least 1");
  if (o.threads == 0 || o.threads > 64) throw UsageError("--threads must be in [1, 64]");
  if (!(o.vmax_kmh > 0.0 && o.vmax_kmh <= 400.0)) throw UsageError("--vmax-kmh must be in (0, 400]");
  planner::AnalyticalOptions options;
  options.seed = o.seed;
  options.runs = o.runs;
  options.level_runs = o.level_runs;
  options.pairs = o.pairs;
  options.threads = o.threads;
  options.vehicle.vmax_mps = o.vmax_kmh / 3.6;
  options.out_dir = o.out_dir;
  if (o.map_signals == "junctions") {
    options.map_signals = planner::MapSignals::junctions;
  } else if (o.map_signals == "mapped") {
    options.map_signals = planner::MapSignals::mapped;
  } else {
    throw UsageError("--map-signals must be junctions or mapped, got '" + o.map_signals + "'");
  }
  try {
    std::filesystem::create_directories(options.out_dir);
  } catch (const std::filesystem::filesystem_error& e) {
    throw UsageError("--out: cannot create the directory '" + o.out_dir + "': " + e.code().message());
  }

  const auto t0 = std::chrono::steady_clock::now();
  for (const std::string& graph : o.graphs) {
    const auto reports = run_one(graph, options, o.map);
    const std::string md = planner::render_markdown(reports);
    const std::string name = reports.empty() ? "graph" : reports.front().graph;
    const auto report_file = options.out_dir / (name + "_report.md");
    std::ofstream(report_file, std::ios::trunc) << md;
    std::cout << md;
    for (const auto& r : reports) {
      for (const auto& f : r.files) spdlog::info("event=experiment_output file={}", f.string());
    }
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::cout << "All experiments: " << seconds << " s. Output in " << options.out_dir.string() << "\n";
}

}  // namespace

void register_experiment_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("experiment", "Experiments that write tables and plots");
  cmd->require_subcommand(1);
  auto o = std::make_shared<AnalyticalCommandOptions>();
  auto* analytical = cmd->add_subcommand(
      "analytical", "Static vs dynamic routing, with and without preemption, on graphs and maps (the seed paper's Figs. 5-9)");
  analytical->add_option("--graph", o->graphs, "simple, complex, a graph .json file, or an OSM map; repeat for several")
      ->required();
  analytical->add_option("--out", o->out_dir, "output directory for CSV, SVG and Markdown")->required();
  analytical->add_option("--seed", o->seed, "random seed; the same seed writes the same CSV files")->capture_default_str();
  analytical->add_option("--runs", o->runs, "runs of Figs. 7-9 on a hand-made graph")->capture_default_str();
  analytical->add_option("--level-runs", o->level_runs, "runs per congestion level, Figs. 5 and 6")->capture_default_str();
  analytical->add_option("--pairs", o->pairs, "start/goal pairs per experiment on a map")->capture_default_str();
  analytical->add_option("--threads", o->threads, "trips simulated in parallel (results do not depend on it)")
      ->capture_default_str();
  analytical->add_option("--vmax-kmh", o->vmax_kmh, "emergency vehicle maximum speed")->capture_default_str();
  analytical->add_option("--map-signals", o->map_signals,
                         "on maps, signal delays at every junction (the paper's model) or only at mapped signals")
      ->capture_default_str();
  analytical->add_option("--cache-dir", o->map.cache_dir, "where imported maps are cached");
  analytical->add_flag("--no-cache", o->map.no_cache, "import maps without reading or writing a cache");
  analytical->callback([o] { run_analytical(*o); });
  register_sumo_experiment(*cmd);
}

}  // namespace corridor::app
