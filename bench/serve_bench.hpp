// `corridor bench serve`: load on the real HTTP server over loopback. Vehicles post positions along
// their mission routes, each on its own connection, back to back or at a fixed total rate, while a
// sensor posts congestion at a fixed edge rate. Reports throughput and latency percentiles as JSON.
#pragma once

#include <nlohmann/json.hpp>

#include "maps/road_graph.hpp"
#include "server/dispatch_service.hpp"

namespace corridor::bench {

struct ServeBenchConfig {
  int vehicles = 200;
  int missions = 50;
  double congestion_edges_per_s = 1000.0;
  int congestion_requests_per_s = 10;
  double seconds = 10.0;
  // Position reports per second over all vehicles, paced evenly; 0 sends back to back (the
  // server's saturation throughput).
  double rate_per_s = 0.0;
  int client_threads = 1;
  int server_threads = 2;
  // Threads that repair plans after a congestion batch, the request's own I/O thread included;
  // 0 = as serve chooses (server::default_repair_threads: half of server_threads, at least 1).
  int repair_threads = 0;
  int repair_realtime_priority = 0;  // DispatchConfig's
  int background_nice = 10;          // DispatchConfig's and ServerLimits::io_nice
  server::PlannerGraph planner_graph = server::PlannerGraph::automatic;
  std::uint64_t seed = 1;
};

// Throws std::invalid_argument for an impossible config, std::runtime_error when the server fails.
nlohmann::json run_serve_bench(const maps::RoadGraph& graph, const ServeBenchConfig& config);

}  // namespace corridor::bench
