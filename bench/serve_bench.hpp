// `corridor bench serve`: load on the real HTTP server over loopback. Vehicles post positions along
// their mission routes as fast as the clients allow, while a sensor posts congestion at a fixed
// edge rate. Reports throughput and client-side latency percentiles as JSON.
#pragma once

#include <nlohmann/json.hpp>

#include "maps/road_graph.hpp"

namespace corridor::bench {

struct ServeBenchConfig {
  int vehicles = 200;
  int missions = 50;
  double congestion_edges_per_s = 1000.0;
  int congestion_requests_per_s = 10;
  double seconds = 10.0;
  int client_threads = 4;
  int server_threads = 2;
  std::uint64_t seed = 1;
};

// Throws std::invalid_argument for an impossible config, std::runtime_error when the server fails.
nlohmann::json run_serve_bench(const maps::RoadGraph& graph, const ServeBenchConfig& config);

}  // namespace corridor::bench
