// `corridor bench replan`: vehicles drive their routes while congestion updates arrive; after each
// batch D* Lite repairs its plan and A* and Dijkstra replan from scratch. Reports per-replan
// latencies, speedups measured in the same run, and D* Lite's mismatches against Dijkstra.
#pragma once

#include <cstdint>
#include <ostream>
#include <vector>
#include <nlohmann/json.hpp>

#include "maps/road_graph.hpp"

namespace corridor::bench {

struct ReplanBenchConfig {
  std::uint32_t trips = 50;
  std::uint32_t updates_per_batch = 20;
  std::uint64_t seed = 1;
  double drive_step_s = 10.0;      // driving time between two update batches
  double vmax_kmh = 120.0;
  // Where each update lands: on the current route, on an edge touching one of its intersections,
  // or anywhere. Routes use main roads, where congestion concentrates, hence more than a uniform
  // share. Of the updates, `clearing_fraction` clear an already congested edge (cost decreases),
  // 3 % close an edge, and the rest slow an edge down (factor 1-4, half with a queue of 0-60 s).
  double on_route_fraction = 0.10;
  double near_route_fraction = 0.20;
  double clearing_fraction = 0.35;
  double min_trip_m = 0.0;         // straight-line; 0 = a third of the map's diagonal, at most 5 km
  bool run_dijkstra = true;
  bool lazy_raises = false;        // D* Lite's lazy raises (DStarLiteOptions); default: the eager paper version
  // D* Lite on the contraction hierarchy, with the metric customized eagerly (dstar_cch) and with
  // lazy rises (dstar_cch_lazy); each can be left out (a grid's hierarchy is slow to customize).
  bool eager_hierarchy = true;
  bool lazy_hierarchy = true;
  std::uint32_t max_replans_per_trip = 1000;
};

struct LatencySummary {
  std::size_t count = 0;
  double p50_ms = 0;
  double p95_ms = 0;
  double p99_ms = 0;
  double max_ms = 0;
  double mean_ms = 0;
};

LatencySummary summarize_ms(std::vector<double> samples_ms);
nlohmann::json to_json(const LatencySummary& s);

// One replan, for finding where the tail's time goes (`--samples-csv`).
struct ReplanSample {
  std::uint32_t trip = 0;
  std::uint32_t step = 0;
  double dstar_ms = 0;
  double astar_ms = 0;
  double dijkstra_ms = 0;
  std::uint64_t dstar_expanded = 0;
  std::uint64_t dstar_raised = 0;
  std::uint64_t astar_settled = 0;
  std::uint64_t dstar_path_checks = 0;
  std::size_t route_edges_before = 0;
  bool reachable = true;
  double cch_customization_ms = 0;
  double cch_repair_ms = 0;
  std::uint64_t cch_expanded = 0;
  std::uint64_t cch_changed_arcs = 0;
  double lazy_customization_ms = 0;
  double lazy_repair_ms = 0;
  std::uint32_t lazy_repairs = 0;
};

struct ReplanBenchResult {
  std::size_t nodes = 0;
  std::size_t edges = 0;
  std::size_t landmarks = 0;
  std::size_t trips = 0;
  std::size_t replans = 0;
  std::size_t mismatches = 0;  // |D* Lite − Dijkstra| > 1e-9 relative
  std::size_t astar_mismatches = 0;
  std::size_t route_changes = 0;  // replans after which D* Lite's route differs from before
  LatencySummary dstar, astar, dijkstra;
  LatencySummary dstar_initial, astar_initial;
  double dstar_mean_expanded = 0;
  double dstar_bytes_per_planner = 0;      // mean over trips, at the trip's end (DStarLite::memory_bytes)
  double dstar_max_bytes_per_planner = 0;
  double dstar_mean_rekeyed = 0;
  double dstar_mean_raised = 0;
  double dstar_mean_path_checks = 0;  // lazy raises: path walks per replan
  double astar_mean_settled = 0;
  double dijkstra_mean_settled = 0;
  // D* Lite on the contraction hierarchy (CchDStarLite): a replan is the metric's partial
  // customization for the batch, then the mission's repair.
  double cch_preprocessing_s = 0;      // nested-dissection order and contraction, once per map
  std::size_t cch_arcs = 0;
  std::size_t cch_topology_bytes = 0;
  std::size_t cch_metric_bytes = 0;
  LatencySummary cch_customization_full;  // once per trip (a fresh overlay)
  LatencySummary cch_dstar, cch_customization, cch_repair, cch_dstar_initial;
  double cch_mean_changed_arcs = 0;      // arcs whose weight a batch moved
  double cch_mean_expanded = 0;
  double cch_mean_vertices = 0;          // the mission's slice: upward + downward half
  double cch_mean_searched_vertices = 0;  // D* Lite's graph in it: the downward half, S and G
  double cch_bytes_per_planner = 0;
  double cch_max_bytes_per_planner = 0;
  std::size_t cch_mismatches = 0;
  // The same on a metric with lazy rises (planner/settled_replan.hpp): the customization carries
  // only decreases up; the repair settles the rises its routes meet and repairs again.
  LatencySummary lazy_dstar, lazy_customization, lazy_repair;
  double lazy_mean_changed_arcs = 0;  // arcs the customization lowered
  double lazy_mean_repairs = 0;       // D* Lite repairs per replan (1: the first route held)
  double lazy_mean_settled = 0;       // arcs settling raised, per replan
  std::uint64_t lazy_max_repairs = 0;
  double lazy_bytes_per_planner = 0;
  std::size_t lazy_metric_bytes = 0;   // with its batch stamps and parent array
  LatencySummary lazy_customization_full;
  std::size_t lazy_mismatches = 0;
  std::vector<ReplanSample> samples;
};

// trip,step,dstar_ms,astar_ms,dijkstra_ms,dstar_expanded,dstar_raised,astar_settled,route_edges_before,reachable,
// dstar_path_checks,cch_customization_ms,cch_repair_ms,cch_expanded,cch_changed_arcs,lazy_customization_ms,
// lazy_repair_ms,lazy_repairs
void write_samples_csv(std::ostream& out, const std::vector<ReplanSample>& samples);

// Throws std::invalid_argument for a config that cannot run (no trips, negative fractions, ...).
ReplanBenchResult run_replan_bench(const maps::RoadGraph& graph, const ReplanBenchConfig& config);

nlohmann::json to_json(const ReplanBenchResult& result, const ReplanBenchConfig& config);

}  // namespace corridor::bench
