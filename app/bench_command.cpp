#include "app/bench_command.hpp"

#include "app/match_command.hpp"

#include <cmath>
#include <fstream>
#include <iostream>
#include <memory>

#include "app/cli_error.hpp"
#include "app/map_options.hpp"
#include "app/serve_command.hpp"
#include "bench/replan_bench.hpp"
#include "bench/serve_bench.hpp"
#include "maps/synthetic_grid.hpp"

namespace corridor::app {
namespace {

struct ReplanOptions {
  MapOptions map;
  bench::ReplanBenchConfig config;
  std::uint32_t synthetic_grid_nodes = 0;
  std::string samples_csv;
};

void run_replan(const ReplanOptions& o) {
  if (o.config.trips == 0) throw UsageError("--trips must be at least 1");
  if (o.config.updates_per_batch == 0) throw UsageError("--updates must be at least 1");
  if (!(o.config.vmax_kmh > 0 && o.config.vmax_kmh <= 400)) throw UsageError("--vmax-kmh must be in (0, 400]");
  nlohmann::json out;
  std::ofstream samples;
  if (!o.samples_csv.empty()) {
    samples.open(o.samples_csv);
    if (!samples) throw UsageError("cannot write --samples-csv '" + o.samples_csv + "'");
  }
  auto finish = [&](const bench::ReplanBenchResult& r) {
    if (samples.is_open()) bench::write_samples_csv(samples, r.samples);
    return bench::to_json(r, o.config);
  };
  if (o.synthetic_grid_nodes > 0) {
    if (!o.map.map_file.empty()) throw UsageError("give either --map or --synthetic-grid, not both");
    maps::GridSpec spec;
    spec.rows = spec.cols = static_cast<std::uint32_t>(std::ceil(std::sqrt(o.synthetic_grid_nodes)));
    spec.seed = o.config.seed;
    const maps::RoadGraph graph = maps::make_perturbed_grid(spec);
    out = finish(bench::run_replan_bench(graph, o.config));
    out["map"] = "synthetic perturbed grid " + std::to_string(spec.rows) + "x" + std::to_string(spec.cols);
  } else {
    const maps::RoadGraph graph = load_map_from_options(o.map);
    out = finish(bench::run_replan_bench(graph, o.config));
    out["map"] = o.map.map_file.empty() ? "embedded monaco.osm.gz" : o.map.map_file;
  }
  std::cout << out.dump(2) << '\n';
}

}  // namespace

void register_bench_command(CLI::App& app) {
  auto* bench_cmd = app.add_subcommand("bench", "Benchmarks that print JSON");
  register_match_bench(*bench_cmd);
  bench_cmd->require_subcommand(1);
  auto o = std::make_shared<ReplanOptions>();
  auto* replan = bench_cmd->add_subcommand("replan", "D* Lite repair vs A*/Dijkstra from scratch while driving");
  add_map_options(*replan, o->map);
  replan->add_option("--synthetic-grid", o->synthetic_grid_nodes,
                     "instead of --map: a perturbed grid with about this many nodes (e.g. 250000)");
  replan->add_option("--trips", o->config.trips, "simulated trips")->capture_default_str();
  replan->add_option("--updates", o->config.updates_per_batch, "congestion updates per batch")->capture_default_str();
  replan->add_option("--seed", o->config.seed, "random seed")->capture_default_str();
  replan->add_option("--drive-step-s", o->config.drive_step_s, "driving time between batches")->capture_default_str();
  replan->add_option("--vmax-kmh", o->config.vmax_kmh, "vehicle maximum speed")->capture_default_str();
  replan->add_option("--on-route", o->config.on_route_fraction, "share of updates on the current route")
      ->capture_default_str();
  replan->add_option("--near-route", o->config.near_route_fraction, "share on edges touching the route")
      ->capture_default_str();
  replan->add_option("--clearing", o->config.clearing_fraction, "share that clear congestion (cost decreases)")
      ->capture_default_str();
  replan->add_option("--min-trip-m", o->config.min_trip_m, "minimum straight-line trip length (0 = auto)");
  replan->add_option("--samples-csv", o->samples_csv, "also write one CSV row per replan (times, expansions)");
  replan->add_flag("!--no-dijkstra", o->config.run_dijkstra, "skip the Dijkstra baseline (and the mismatch check)");
  replan->add_flag("--lazy-raises", o->config.lazy_raises,
                   "D* Lite repairs cost increases only where they reach the path (Delayed D*), not at once");
  replan->add_option_function<std::string>(
             "--hierarchy",
             [o](const std::string& v) {
               o->config.eager_hierarchy = v == "both" || v == "eager";
               o->config.lazy_hierarchy = v == "both" || v == "lazy";
             },
             "D* Lite on the contraction hierarchy: its metric customized eagerly, with lazy rises, both, or none "
             "(default both)")
      ->check(CLI::IsMember({"both", "eager", "lazy", "none"}));
  replan->callback([o] { run_replan(*o); });

  auto s = std::make_shared<std::pair<MapOptions, bench::ServeBenchConfig>>();
  auto* serve = bench_cmd->add_subcommand("serve", "Load on the HTTP server over loopback: positions and congestion");
  add_map_options(*serve, s->first);
  serve->add_option("--vehicles", s->second.vehicles, "vehicles posting positions")->capture_default_str();
  serve->add_option("--missions", s->second.missions, "of which with an active mission")->capture_default_str();
  serve->add_option("--congestion-edges-per-s", s->second.congestion_edges_per_s, "congested edges per second")
      ->capture_default_str();
  serve->add_option("--seconds", s->second.seconds, "duration of the load")->capture_default_str();
  serve->add_option("--rate", s->second.rate_per_s, "position reports per second, paced (0 = back to back)")
      ->capture_default_str();
  serve->add_option("--client-threads", s->second.client_threads, "load generator threads")->capture_default_str();
  serve->add_option("--server-threads", s->second.server_threads, "server I/O threads")->capture_default_str();
  serve->add_option("--repair-threads", s->second.repair_threads,
                    "threads repairing plans after a congestion batch, its request's I/O thread included (0 = as serve "
                    "chooses: half of --server-threads, at least 1)")
      ->capture_default_str();
  serve->add_option("--repair-priority", s->second.repair_realtime_priority,
                    "0, or the real-time (SCHED_FIFO) priority of repairs, as serve's --repair-priority")
      ->check(CLI::Range(0, 99))
      ->capture_default_str();
  serve->add_option("--background-nice", s->second.background_nice,
                    "nice steps the server's I/O threads and commit writer take below its repairs, as serve's "
                    "--background-nice (the load generator's threads keep theirs)")
      ->check(CLI::Range(0, 19))
      ->capture_default_str();
  add_planner_graph_option(*serve, s->second.planner_graph);
  serve->callback([s] {
    const maps::RoadGraph graph = load_map_from_options(s->first);
    auto out = bench::run_serve_bench(graph, s->second);
    out["map"] = s->first.map_file.empty() ? "embedded monaco.osm.gz" : s->first.map_file;
    std::cout << out.dump(2) << '\n';
  });
}

}  // namespace corridor::app
