// The seed paper's analytical study as a command: Figs. 5-9 on the hand-made graphs, and the same
// protocol on real maps. Each experiment writes a CSV of every trip, a CSV of medians, and a plot.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "planner/experiments/analytical_graph.hpp"
#include "planner/experiments/scenario_generator.hpp"

namespace corridor::planner {

// Where a real map's signal delays sit when there is no preemption.
enum class MapSignals {
  junctions,  // every intersection of three or more roads, as in the paper's model
  mapped,     // only the intersections mapped with traffic signals in OSM
};

struct AnalyticalOptions {
  std::uint64_t seed = 1;
  std::uint32_t runs = 10;         // runs of Figs. 7-9 on a hand-made graph (the paper shows ten)
  std::uint32_t level_runs = 100;  // runs per congestion level, Figs. 5 and 6
  std::uint32_t pairs = 1000;      // start/goal pairs per experiment on a real map
  VehicleProfile vehicle;          // 120 km/h, as in the paper
  MapSignals map_signals = MapSignals::junctions;
  unsigned threads = 1;            // trips evaluated in parallel; results do not depend on it
  std::filesystem::path out_dir;
};

// The four strategies, in the order of every table and plot.
struct Strategy {
  Routing routing;
  Signals signals;
};
inline constexpr Strategy kStrategies[] = {{Routing::static_route, Signals::no_preemption},
                                           {Routing::dynamic_route, Signals::no_preemption},
                                           {Routing::static_route, Signals::preemption},
                                           {Routing::dynamic_route, Signals::preemption}};
std::string strategy_label(const Strategy& s);

struct StrategySummary {
  double level_min = -1.0;  // the congestion level, or -1 for experiments without one
  Strategy strategy;
  std::uint32_t runs = 0;
  double median_travel_s = 0.0;
  double median_increase_pct = 0.0;
  double mean_increase_pct = 0.0;
  // Dynamic strategies only: how it went against static routing with the same signals.
  std::uint32_t worse_than_static = 0;
  std::uint32_t better_than_static = 0;
  std::uint32_t rerouted = 0;
  std::uint64_t replans = 0;
  std::uint64_t route_changes = 0;
  double replan_wall_s = 0.0;  // not deterministic: kept out of the CSV files
};

struct ExperimentReport {
  std::string graph;
  std::string experiment;  // fig5, fig6, fig7, fig8a, fig8b, fig9, levels
  std::string title;
  std::vector<StrategySummary> summaries;
  std::vector<std::filesystem::path> files;
  double wall_s = 0.0;
};

// Figs. 5 ("simple") or 6-9 (any other hand-made graph).
std::vector<ExperimentReport> run_graph_experiments(const AnalyticalGraph& graph, const AnalyticalOptions& options);

// The same protocol on a real road graph: random pairs, signal delays at its signalized
// intersections, congestion on and near each planned route.
std::vector<ExperimentReport> run_map_experiments(const maps::RoadGraph& graph, const std::string& name,
                                                  const AnalyticalOptions& options);

// Markdown tables of the medians, for docs/experiments/analytical.md.
std::string render_markdown(const std::vector<ExperimentReport>& reports);

}  // namespace corridor::planner
