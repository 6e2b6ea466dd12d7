#include "app/match_command.hpp"

#include <chrono>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>

#include <nlohmann/json.hpp>

#include "app/cli_error.hpp"
#include "app/map_options.hpp"
#include "localizer/match/hmm_matcher.hpp"
#include "localizer/match/synthetic_trace.hpp"
#include "localizer/match/trace_io.hpp"
#include "localizer/study/localization_study.hpp"
#include "planner/route.hpp"

namespace corridor::app {
namespace {

using nlohmann::json;

struct MatchOptions {
  MapOptions map;
  std::string trace;
  std::string out;
  bool json = false;
};

double round7(double v) { return std::round(v * 1e7) / 1e7; }

json lon_lat(const maps::RoadGraph& g, maps::Point2 p) {
  const maps::LatLon ll = g.projection().to_lat_lon(p);
  return json::array({round7(ll.lon_deg), round7(ll.lat_deg)});
}

// The matched path through consecutive matched points: along the edge, or from one edge's point to
// its end and on from the next edge's start where they meet; a break starts a new line.
json matched_route(const maps::RoadGraph& g, const std::vector<localizer::MatchedPoint>& points) {
  json lines = json::array();
  json line = json::array();
  const localizer::MatchedPoint* prev = nullptr;
  auto close = [&] {
    if (line.size() >= 2) lines.push_back(line);
    line = json::array();
  };
  for (const auto& m : points) {
    if (!m.matched) {
      close();
      prev = nullptr;
      continue;
    }
    if (m.chain_start) close();
    if (line.empty() || prev == nullptr) {
      line.push_back(lon_lat(g, g.point_along(m.edge, m.offset_m)));
    } else if (prev->edge == m.edge && m.offset_m >= prev->offset_m) {
      for (const auto& p : planner::edge_polyline(g, m.edge, prev->offset_m, m.offset_m)) line.push_back(lon_lat(g, p));
    } else {
      for (const auto& p : planner::edge_polyline(g, prev->edge, prev->offset_m, g.length_m(prev->edge))) line.push_back(lon_lat(g, p));
      for (const auto& p : planner::edge_polyline(g, m.edge, 0.0, m.offset_m)) line.push_back(lon_lat(g, p));
    }
    prev = &m;
  }
  close();
  if (lines.size() == 1) return {{"type", "LineString"}, {"coordinates", lines[0]}};
  return {{"type", "MultiLineString"}, {"coordinates", lines}};
}

void run_match(const MatchOptions& o) {
  const maps::RoadGraph graph = load_map_from_options(o.map);
  localizer::TraceTiming timing = localizer::TraceTiming::measured;
  const std::vector<localizer::GpsFix> trace = localizer::read_trace(o.trace, &timing);
  const bool timed = timing == localizer::TraceTiming::measured;
  if (!timed) {
    std::cerr << "corridor match: the trace has no timing (no <time>, or one time for every point): matched by its geometry alone\n";
  }
  const maps::EdgeSnapper snapper(graph);
  localizer::HmmMatcher matcher(graph, snapper);
  const auto started = std::chrono::steady_clock::now();
  const auto matched = matcher.match(trace);
  const double took_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();

  json points = json::array();
  json way_names = json::array();
  std::size_t matched_count = 0;
  for (std::size_t i = 0; i < matched.size(); ++i) {
    const auto& m = matched[i];
    json p{{"time_s", timed ? json(trace[i].time_s) : json(nullptr)}, {"matched", m.matched}, {"outlier", m.outlier}};
    if (m.matched) {
      ++matched_count;
      const maps::LatLon at = graph.projection().to_lat_lon(m.point);
      p["lat"] = round7(at.lat_deg);
      p["lon"] = round7(at.lon_deg);
      p["edge"] = m.edge.v;
      p["osm_way_id"] = graph.osm_way(m.edge).v;
      p["name"] = graph.name(m.edge);
      p["offset_m"] = std::round(m.offset_m * 100.0) / 100.0;
      p["distance_m"] = std::round(m.distance_m * 100.0) / 100.0;
      p["confidence"] = std::round(m.confidence * 1000.0) / 1000.0;
      const std::string name(graph.name(m.edge));
      if (!name.empty() && (way_names.empty() || way_names.back() != name)) way_names.push_back(name);
    } else {
      p["lat"] = trace[i].position.lat_deg;
      p["lon"] = trace[i].position.lon_deg;
      p["edge"] = nullptr;
      p["osm_way_id"] = nullptr;
      p["name"] = nullptr;
      p["offset_m"] = nullptr;
      p["distance_m"] = nullptr;
    }
    points.push_back(std::move(p));
  }
  if (matched_count == 0) {
    throw localizer::TraceError("no fix of the trace is within reach of a road on this map (is it the right map?)");
  }
  const json route = matched_route(graph, matched);
  const double per_s = took_s > 0.0 ? static_cast<double>(trace.size()) / took_s : 0.0;
  if (!o.out.empty()) {
    std::ofstream out(o.out);
    if (!out) throw UsageError("cannot write --out '" + o.out + "'");
    out << json{{"type", "Feature"},
                {"geometry", route},
                {"properties", {{"fixes", trace.size()}, {"matched", matched_count}, {"timing", timed ? "measured" : "none"}}}}
               .dump()
        << '\n';
  }
  if (o.json) {
    std::cout << json{{"points", std::move(points)},
                      {"way_names", way_names},
                      {"route", route},
                      {"fixes", trace.size()},
                      {"matched", matched_count},
                      {"timing", timed ? "measured" : "none"},
                      {"points_per_s", per_s}}
                     .dump()
              << '\n';
    return;
  }
  std::cout << matched_count << " of " << trace.size() << " fixes matched (" << static_cast<long>(per_s) << " fixes/s)"
            << (timed ? "" : ", by geometry alone: the trace has no timing") << "\n";
  std::cout << "streets:";
  for (const auto& n : way_names) std::cout << " " << n.get<std::string>() << " →";
  std::cout << (way_names.empty() ? " (unnamed)\n" : " end\n");
}

struct MatchBenchOptions {
  MapOptions map;
  std::vector<std::string> fcd;
  std::string prefix;
  double outage_s = 60.0;
  std::string plot;
  std::string plot_id;
  std::string csv;
  int drives = 20;
  std::size_t edges = 60;
  double noise_m = 5.0;
  double outliers = 0.0;
  std::uint64_t seed = 1;
  localizer::VoDriftModel odometry;  // the study's simulated odometry errors
  bool scale_calibration = true;     // the fusion calibrates the odometry's scale by the receiver's speed
};

json drive_json(const localizer::DriveResult& d) {
  auto ratio = [](double a, double b) { return b > 0.0 ? a / b : 0.0; };
  auto rmse = [](double sq, std::size_t n) { return n > 0 ? std::sqrt(sq / static_cast<double>(n)) : 0.0; };
  const double truth = static_cast<double>(d.with_truth);
  return {{"id", d.id},
          {"samples", d.samples},
          {"length_m", std::round(d.length_m)},
          {"rmse_raw_m", rmse(d.sq_raw, d.n_raw)},
          {"rmse_nearest_m", rmse(d.sq_nearest, d.n_raw)},
          {"rmse_hmm_m", rmse(d.sq_hmm, d.n_hmm)},
          {"hmm_matched_share", ratio(static_cast<double>(d.n_hmm), static_cast<double>(d.n_raw))},
          // The HMM's RMSE over its matched fixes that have a true edge; the share of fixes (outside
          // the outage) with a true edge.
          {"rmse_hmm_on_graph_m", rmse(d.sq_hmm_on_graph, d.n_hmm_on_graph)},
          {"on_graph_share", ratio(truth, static_cast<double>(d.n_raw))},
          {"rmse_fused_m", rmse(d.sq_fused, d.n_fused)},
          {"correct_edge_hmm_by_time", ratio(static_cast<double>(d.correct_hmm), truth)},
          {"correct_edge_hmm_by_length", ratio(d.length_correct_hmm, d.length_with_truth)},
          {"correct_road_hmm", ratio(static_cast<double>(d.correct_hmm_road), truth)},
          {"correct_road_nearest", ratio(static_cast<double>(d.correct_nearest_road), truth)},
          {"correct_edge_fused_by_time", ratio(static_cast<double>(d.correct_fused), truth)},
          {"outage_samples", d.outage_samples},
          {"outage_correct_edge_share", ratio(static_cast<double>(d.outage_correct), static_cast<double>(d.outage_samples))},
          {"outage_rmse_m", rmse(d.outage_sq, d.outage_samples)},
          // The same shares against the nearest-road oracle alone (no SUMO lane), for comparison.
          {"correct_edge_hmm_by_time_nearest_oracle",
           ratio(static_cast<double>(d.correct_hmm_nearest_oracle), static_cast<double>(d.with_truth_nearest_oracle))},
          {"outage_correct_edge_share_nearest_oracle",
           ratio(static_cast<double>(d.outage_correct_nearest_oracle), static_cast<double>(d.outage_samples_nearest_oracle))},
          {"truth_from_lane_share", ratio(static_cast<double>(d.truth_from_lane), static_cast<double>(d.samples))},
          {"recovery_s", d.recovery_s},
          {"handback_jump_m", d.handback_jump_m},
          // The odometry's scale error as the outage begins (RMS over drives): as simulated, and
          // after the fusion's calibration against the receiver's speed.
          {"odometry_scale_error_raw", rmse(d.scale_sq_raw, d.scale_n)},
          {"odometry_scale_error", rmse(d.scale_sq_calibrated, d.scale_n)}};
}

void run_fcd_study(const MatchBenchOptions& o) {
  if (!(o.noise_m >= 0.0) || !(o.outliers >= 0.0 && o.outliers <= 1.0) || !(o.outage_s >= 0.0)) {
    throw UsageError("--noise-m and --outage-s must be >= 0 and --outliers within [0, 1]");
  }
  if (!(o.odometry.scale_sigma >= 0.0 && o.odometry.scale_sigma < 0.2) || !(o.odometry.heading_deg_per_100m >= 0.0) ||
      !(o.odometry.heading_deg_per_100m < 90.0)) {
    throw UsageError("--odometry-scale-sigma must be within [0, 0.2) and --odometry-heading-deg-per-100m within [0, 90)");
  }
  const maps::RoadGraph graph = load_map_from_options(o.map);
  const maps::EdgeSnapper snapper(graph);
  std::map<std::string, std::vector<localizer::TruthSample>> drives;
  for (const std::string& file : o.fcd) {
    for (auto& [id, samples] : localizer::read_fcd(file, o.prefix)) drives[file + ":" + id] = std::move(samples);
  }
  if (drives.empty()) throw UsageError("no vehicle in the fcd file(s) matches --prefix '" + o.prefix + "'");
  localizer::StudyConfig config;
  config.noise_sigma_m = o.noise_m;
  config.outlier_share = o.outliers;
  config.outage_s = o.outage_s;
  config.seed = o.seed;
  config.odometry = o.odometry;
  config.localizer.odometry_scale.enabled = o.scale_calibration;
  localizer::DrivePlot plot;
  const std::string plot_id = o.plot_id.empty() ? drives.begin()->first : o.plot_id;
  const auto started = std::chrono::steady_clock::now();
  const auto result = localizer::run_localization_study(graph, snapper, drives, config, plot_id, o.plot.empty() ? nullptr : &plot);
  const double took_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  json list = json::array();
  for (const auto& d : result.drives) list.push_back(drive_json(d));
  if (!o.csv.empty()) {
    std::ofstream csv(o.csv);
    if (!csv) throw UsageError("cannot write --csv '" + o.csv + "'");
    bool header = true;
    for (const auto& d : list) {
      if (header) {
        bool first = true;
        for (const auto& [k, v] : d.items()) csv << (first ? "" : ",") << k, first = false;
        csv << '\n';
        header = false;
      }
      bool first = true;
      for (const auto& [k, v] : d.items()) csv << (first ? "" : ",") << (v.is_string() ? v.get<std::string>() : v.dump()), first = false;
      csv << '\n';
    }
  }
  if (!o.plot.empty()) {
    std::ofstream svg(o.plot);
    if (!svg) throw UsageError("cannot write --plot '" + o.plot + "'");
    svg << localizer::drive_plot_svg(graph, plot, plot_id);
  }
  json out{{"map", o.map.map_file.empty() ? "embedded" : o.map.map_file},
           {"drives", result.drives.size()},
           {"noise_sigma_m", o.noise_m},
           {"outlier_share", o.outliers},
           {"outage_s", o.outage_s},
           {"total", drive_json(result.total)},
           {"per_drive", std::move(list)},
           {"seconds", took_s}};
  std::cout << out.dump(2) << '\n';
}

void run_match_bench(const MatchBenchOptions& o) {
  if (!o.fcd.empty()) return run_fcd_study(o);
  if (o.drives < 1 || o.edges < 2) throw UsageError("--drives must be at least 1 and --edges at least 2");
  if (!(o.noise_m >= 0.0) || !(o.outliers >= 0.0 && o.outliers <= 1.0)) {
    throw UsageError("--noise-m must be >= 0 and --outliers within [0, 1]");
  }
  const maps::RoadGraph graph = load_map_from_options(o.map);
  const maps::EdgeSnapper snapper(graph);
  std::vector<localizer::SyntheticTrace> traces;
  for (int d = 0; d < o.drives; ++d) {
    localizer::SyntheticTraceSpec spec;
    spec.edges = o.edges;
    spec.noise_sigma_m = o.noise_m;
    spec.outlier_share = o.outliers;
    spec.seed = o.seed + static_cast<std::uint64_t>(d);
    traces.push_back(localizer::make_synthetic_trace(graph, spec));
  }
  std::size_t fixes = 0, correct = 0, nearest_correct = 0, matched = 0;
  double batch_s = 0.0, online_s = 0.0, sq_err = 0.0, sq_raw = 0.0, sq_nearest = 0.0;
  for (const auto& t : traces) {
    localizer::HmmMatcher batch(graph, snapper);
    auto started = std::chrono::steady_clock::now();
    const auto result = batch.match(t.fixes);
    batch_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    localizer::HmmMatcher online(graph, snapper);
    started = std::chrono::steady_clock::now();
    for (const auto& f : t.fixes) (void)online.update(f);
    online_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    for (std::size_t i = 0; i < t.fixes.size(); ++i) {
      ++fixes;
      const maps::Point2 raw = graph.projection().to_local(t.fixes[i].position);
      sq_raw += std::pow(maps::distance_m(raw, t.truth_point[i]), 2);
      const auto near = snapper.snap_local(raw);
      nearest_correct += near.edge == t.truth[i] ? 1 : 0;
      sq_nearest += std::pow(maps::distance_m(near.point, t.truth_point[i]), 2);
      if (result[i].matched) {
        ++matched;
        sq_err += std::pow(maps::distance_m(result[i].point, t.truth_point[i]), 2);
        if (result[i].edge == t.truth[i]) ++correct;
      }
    }
  }
  const double n = static_cast<double>(fixes);
  json out{{"map", o.map.map_file.empty() ? "embedded" : o.map.map_file},
           {"drives", o.drives},
           {"fixes", fixes},
           {"noise_sigma_m", o.noise_m},
           {"outlier_share", o.outliers},
           {"matched_share", static_cast<double>(matched) / n},
           {"correct_edge_share", static_cast<double>(correct) / n},
           {"nearest_edge_correct_share", static_cast<double>(nearest_correct) / n},
           {"rmse_raw_m", std::sqrt(sq_raw / n)},
           {"rmse_nearest_m", std::sqrt(sq_nearest / n)},
           {"rmse_matched_m", matched > 0 ? std::sqrt(sq_err / static_cast<double>(matched)) : 0.0},
           {"batch_fixes_per_s", batch_s > 0.0 ? n / batch_s : 0.0},
           {"online_fixes_per_s", online_s > 0.0 ? n / online_s : 0.0}};
  std::cout << out.dump(2) << '\n';
}

}  // namespace

void register_match_command(CLI::App& app) {
  auto o = std::make_shared<MatchOptions>();
  auto* cmd = app.add_subcommand("match", "Map-match a GPS trace (GPX, or CSV time,lat,lon[,hdop,heading_deg,speed_mps])");
  add_map_options(*cmd, o->map);
  cmd->add_option("--trace", o->trace, "GPX or CSV trace")->required();
  cmd->add_flag("--json", o->json, "print points, way_names, route and points_per_s as JSON");
  cmd->add_option("--out", o->out, "write the matched route as a GeoJSON Feature");
  cmd->callback([o] { run_match(*o); });
}

void register_match_bench(CLI::App& bench) {
  auto o = std::make_shared<MatchBenchOptions>();
  auto* cmd = bench.add_subcommand("match", "HMM map matching on synthetic noisy drives: fixes/s, correct edges, RMSE");
  add_map_options(*cmd, o->map);
  cmd->add_option("--drives", o->drives, "drives (random walks)")->capture_default_str();
  cmd->add_option("--edges", o->edges, "edges per drive")->capture_default_str();
  cmd->add_option("--noise-m", o->noise_m, "GPS noise σ in metres")->capture_default_str();
  cmd->add_option("--outliers", o->outliers, "share of multipath outliers (60 m off)")->capture_default_str();
  cmd->add_option("--seed", o->seed, "first drive's seed")->capture_default_str();
  cmd->add_option("--fcd", o->fcd, "SUMO fcd output (geo) as ground truth: the accuracy study instead of random walks");
  cmd->add_option("--prefix", o->prefix, "with --fcd: only vehicles whose id starts with this");
  cmd->add_option("--outage-s", o->outage_s, "with --fcd: one GPS outage of this length per drive")->capture_default_str();
  cmd->add_option("--plot", o->plot, "with --fcd: an SVG of one drive");
  cmd->add_option("--plot-id", o->plot_id, "with --fcd: the drive to plot (FILE:VEHICLE; default the first)");
  cmd->add_option("--csv", o->csv, "with --fcd: per-drive figures as CSV");
  cmd->add_option("--odometry-scale-sigma", o->odometry.scale_sigma,
                  "with --fcd: 1σ of the simulated odometry's per-drive scale error (0.0062: our VO's t_err)")
      ->capture_default_str();
  cmd->add_option("--odometry-heading-deg-per-100m", o->odometry.heading_deg_per_100m,
                  "with --fcd: 1σ of the simulated odometry's heading random walk per 100 m (our VO's r_err)")
      ->capture_default_str();
  cmd->add_flag("!--no-scale-calibration", o->scale_calibration,
                "with --fcd: the fusion takes the odometry's distances as reported, without calibrating them by the receiver's speed");
  cmd->callback([o] { run_match_bench(*o); });
}

}  // namespace corridor::app
