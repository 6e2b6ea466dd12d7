#include "planner/experiments/analytical_experiments.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <fstream>
#include <functional>
#include <optional>
#include <stdexcept>
#include <thread>

#include "planner/experiments/statistics.hpp"
#include "planner/experiments/svg_chart.hpp"

namespace corridor::planner {
namespace {

enum class Kind { levels, runs };
enum class Plot { levels_minutes, levels_percent, bars_percent, bars_minutes, cdf_percent };

struct ExperimentSpec {
  std::string id;
  std::string title;
  Kind kind = Kind::runs;
  bool random_pairs = false;
  bool fixed_sites = false;  // the same congested links in every run ("on the same links")
  DelayRange signal{180.0, 180.0};
  DelayRange queue{0.0, 420.0};
  std::vector<double> levels_min;
  CongestionPlacement placement;
  std::uint32_t runs = 10;
  Plot plot = Plot::bars_percent;
};

// What differs between a hand-made graph and a real map.
struct GraphContext {
  const maps::RoadGraph& graph;
  std::string name;
  std::function<std::string(NodeId)> node_name;
  std::vector<std::uint8_t> has_signal;  // where signal delays apply without preemption
  NodeId source;  // the default pair, for experiments without random pairs
  NodeId destination;
  double min_pair_distance_m = 0.0;
  std::uint32_t min_pair_edges = 2;
};

struct Trip {
  std::uint32_t run = 0;
  double level_min = -1.0;
  TripScenario scenario;
  double base_s = 0.0;
  std::array<TripResult, 4> results;
};

constexpr double kMinute = 60.0;
ExperimentSpec named_spec(std::string id, std::string title) {
  ExperimentSpec spec;
  spec.id = std::move(id);
  spec.title = std::move(title);
  return spec;
}

// Fig. 8b (queue delay fixed at 7 min, signal delay random) and Fig. 9 (both random) from the
// protocol of `base`, whose signal delay is fixed at 3 min and queue delay random.
void add_delay_variants(std::vector<ExperimentSpec>& specs, const ExperimentSpec& base, const std::string& suffix) {
  ExperimentSpec fig8b = base;
  fig8b.id = "fig8b";
  fig8b.title = "queue delay 7 min, signal delay 0-3 min" + suffix;
  fig8b.signal = {0.0, 180.0};
  fig8b.queue = {420.0, 420.0};
  specs.push_back(fig8b);
  ExperimentSpec fig9 = base;
  fig9.id = "fig9";
  fig9.title = "signal delay 0-3 min and queue delay 0-7 min" + suffix;
  fig9.signal = {0.0, 180.0};
  specs.push_back(fig9);
}

const std::vector<double> kLevelsMin{0, 1, 2, 3, 4, 5, 6, 7};

double increase_pct(double travel_s, double base_s) { return (travel_s - base_s) / base_s * 100.0; }

void evaluate(std::vector<Trip>& trips, const maps::RoadGraph& graph, const AnalyticalOptions& options) {
  std::atomic<std::size_t> next{0};
  auto work = [&] {
    for (std::size_t i = next++; i < trips.size(); i = next++) {
      for (std::size_t k = 0; k < std::size(kStrategies); ++k) {
        trips[i].results[k] =
            drive_trip(graph, trips[i].scenario, kStrategies[k].routing, kStrategies[k].signals, options.vehicle);
      }
    }
  };
  const unsigned threads = std::max(1u, std::min<unsigned>(options.threads, static_cast<unsigned>(trips.size())));
  std::vector<std::jthread> pool;
  for (unsigned t = 1; t < threads; ++t) pool.emplace_back(work);
  work();
}

std::vector<Trip> make_trips(const GraphContext& ctx, const ExperimentSpec& spec, const AnalyticalOptions& options) {
  Rng rng(derive_seed(options.seed, ctx.name + "/" + spec.id));
  std::vector<Trip> trips;
  std::optional<CongestionSites> fixed;
  for (std::uint32_t r = 0; r < spec.runs; ++r) {
    NodeId s = ctx.source;
    NodeId t = ctx.destination;
    if (spec.random_pairs) {
      std::tie(s, t) = draw_pair(ctx.graph, ctx.min_pair_distance_m, ctx.min_pair_edges, options.vehicle, rng);
    }
    TripScenario scenario{s, t, draw_signal_delays(ctx.has_signal, spec.signal, rng), {}};
    // Congestion is placed and timed along the fastest plan (no signal waits): every jam on it
    // appears before any of the four vehicles can reach it, so none is spared by being quick.
    const Route plan = static_plan(ctx.graph, scenario, Signals::preemption, options.vehicle);
    if (spec.fixed_sites && !fixed) fixed = pick_congestion_sites(ctx.graph, plan, spec.placement, rng);
    const CongestionSites sites = fixed ? *fixed : pick_congestion_sites(ctx.graph, plan, spec.placement, rng);
    scenario.events = draw_events(sites, spec.queue, rng);
    const double base = base_travel_time_s(ctx.graph, s, t, options.vehicle);
    if (spec.kind == Kind::runs) {
      trips.push_back({r, -1.0, std::move(scenario), base, {}});
      continue;
    }
    // Common random numbers: every level sees the same pair, links and times.
    for (double level : spec.levels_min) {
      TripScenario at_level = scenario;
      for (CongestionEvent& e : at_level.events) e.queue_delay_s = level * kMinute;
      trips.push_back({r, level, std::move(at_level), base, {}});
    }
  }
  return trips;
}

std::vector<StrategySummary> summarize(const std::vector<Trip>& trips, const ExperimentSpec& spec) {
  std::vector<double> levels = spec.kind == Kind::levels ? spec.levels_min : std::vector<double>{-1.0};
  std::vector<StrategySummary> out;
  for (double level : levels) {
    for (std::size_t k = 0; k < std::size(kStrategies); ++k) {
      StrategySummary s;
      s.level_min = level;
      s.strategy = kStrategies[k];
      std::vector<double> travel;
      std::vector<double> increase;
      for (const Trip& t : trips) {
        if (t.level_min != level) continue;
        const TripResult& r = t.results[k];
        travel.push_back(r.travel_time_s);
        increase.push_back(increase_pct(r.travel_time_s, t.base_s));
        if (kStrategies[k].routing == Routing::dynamic_route) {
          const double static_s = t.results[k - 1].travel_time_s;
          s.worse_than_static += r.travel_time_s > static_s + 1e-6 ? 1 : 0;
          s.better_than_static += r.travel_time_s < static_s - 1e-6 ? 1 : 0;
          s.rerouted += r.rerouted() ? 1 : 0;
          s.replans += r.replans;
          s.route_changes += r.route_changes;
          s.replan_wall_s += r.replan_wall_s;
        }
      }
      s.runs = static_cast<std::uint32_t>(travel.size());
      s.median_travel_s = quantile(travel, 0.5);
      s.median_increase_pct = quantile(increase, 0.5);
      double sum = 0.0;
      for (double v : increase) sum += v;
      s.mean_increase_pct = increase.empty() ? std::nan("") : sum / static_cast<double>(increase.size());
      out.push_back(s);
    }
  }
  return out;
}

std::string level_text(double level) { return level < 0.0 ? "" : fmt::format("{:g}", level); }

void write_file(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << text;
  out.close();
  if (!out) throw std::runtime_error("cannot write " + path.string());
}

std::string trips_csv(const std::vector<Trip>& trips, const ExperimentSpec& spec, const GraphContext& ctx) {
  std::string csv =
      "experiment,run,level_min,source,destination,base_s,routing,signals,travel_s,increase_pct,signal_wait_s,"
      "queue_wait_s,events,replans,route_changes,rerouted,expanded\n";
  for (const Trip& t : trips) {
    for (std::size_t k = 0; k < std::size(kStrategies); ++k) {
      const TripResult& r = t.results[k];
      csv += fmt::format("{},{},{},{},{},{:.3f},{},{},{:.3f},{:.3f},{:.3f},{:.3f},{},{},{},{},{}\n", spec.id, t.run + 1,
                         level_text(t.level_min), ctx.node_name(t.scenario.source),
                         ctx.node_name(t.scenario.destination), t.base_s, to_string(kStrategies[k].routing),
                         to_string(kStrategies[k].signals), r.travel_time_s, increase_pct(r.travel_time_s, t.base_s),
                         r.signal_wait_s, r.queue_wait_s, t.scenario.events.size(), r.replans, r.route_changes,
                         r.rerouted() ? 1 : 0, r.expanded);
    }
  }
  return csv;
}

std::string summary_csv(const std::vector<StrategySummary>& summaries, const ExperimentSpec& spec) {
  std::string csv =
      "experiment,level_min,routing,signals,runs,median_travel_s,median_increase_pct,mean_increase_pct,"
      "worse_than_static,better_than_static,rerouted,replans,route_changes\n";
  for (const StrategySummary& s : summaries) {
    csv += fmt::format("{},{},{},{},{},{:.3f},{:.3f},{:.3f},{},{},{},{},{}\n", spec.id, level_text(s.level_min),
                       to_string(s.strategy.routing), to_string(s.strategy.signals), s.runs, s.median_travel_s,
                       s.median_increase_pct, s.mean_increase_pct, s.worse_than_static, s.better_than_static,
                       s.rerouted, s.replans, s.route_changes);
  }
  return csv;
}

std::string plot(const std::vector<Trip>& trips, const std::vector<StrategySummary>& summaries,
                 const ExperimentSpec& spec, const GraphContext& ctx) {
  std::vector<ChartSeries> series;
  for (const Strategy& st : kStrategies) series.push_back({strategy_label(st), {}, {}});
  const ChartText text{fmt::format("{}: {}", ctx.name, spec.title), "", ""};
  switch (spec.plot) {
    case Plot::levels_minutes:
    case Plot::levels_percent: {
      const bool minutes = spec.plot == Plot::levels_minutes;
      for (const StrategySummary& s : summaries) {
        const auto k = static_cast<std::size_t>(&s - summaries.data()) % std::size(kStrategies);
        series[k].x.push_back(s.level_min);
        series[k].y.push_back(minutes ? s.median_travel_s / kMinute : s.median_increase_pct);
      }
      return render_line_chart({text.title, "queue delay on each congested link (min)",
                                minutes ? "median travel time (min)" : "median increase over base (%)"},
                               series);
    }
    case Plot::bars_percent:
    case Plot::bars_minutes: {
      const bool minutes = spec.plot == Plot::bars_minutes;
      std::vector<std::string> categories;
      for (const Trip& t : trips) {
        categories.push_back(spec.random_pairs ? ctx.node_name(t.scenario.source) + "-" + ctx.node_name(t.scenario.destination)
                                               : std::to_string(t.run + 1));
        for (std::size_t k = 0; k < std::size(kStrategies); ++k) {
          const double v = t.results[k].travel_time_s;
          series[k].y.push_back(minutes ? v / kMinute : increase_pct(v, t.base_s));
        }
      }
      return render_bar_chart({text.title, spec.random_pairs ? "start-goal pair" : "run",
                               minutes ? "travel time (min)" : "increase over the pair's base (%)"},
                              categories, series);
    }
    case Plot::cdf_percent: {
      // Clip the long tail at the 99th percentile so the bulk stays readable.
      std::vector<double> all;
      for (const Trip& t : trips) {
        for (const TripResult& r : t.results) all.push_back(increase_pct(r.travel_time_s, t.base_s));
      }
      std::sort(all.begin(), all.end());
      const double clip = all.empty() ? 0.0 : all[static_cast<std::size_t>(0.99 * static_cast<double>(all.size() - 1))];
      for (std::size_t k = 0; k < std::size(kStrategies); ++k) {
        std::vector<double> v;
        for (const Trip& t : trips) v.push_back(increase_pct(t.results[k].travel_time_s, t.base_s));
        std::sort(v.begin(), v.end());
        for (std::size_t i = 0; i < v.size(); ++i) {
          if (v[i] > clip) break;
          series[k].x.push_back(v[i]);
          series[k].y.push_back(static_cast<double>(i + 1) / static_cast<double>(v.size()));
        }
      }
      return render_line_chart({text.title + " (CDF)", "increase over the pair's base (%)", "fraction of trips"}, series);
    }
  }
  return {};
}

ExperimentReport run_experiment(const GraphContext& ctx, const ExperimentSpec& spec, const AnalyticalOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<Trip> trips = make_trips(ctx, spec, options);
  evaluate(trips, ctx.graph, options);
  ExperimentReport report{ctx.name, spec.id, spec.title, summarize(trips, spec), {}, 0.0};
  std::filesystem::create_directories(options.out_dir);
  const std::string stem = ctx.name + "_" + spec.id;
  const auto dir = options.out_dir;
  write_file(dir / (stem + ".csv"), trips_csv(trips, spec, ctx));
  write_file(dir / (stem + "_summary.csv"), summary_csv(report.summaries, spec));
  write_file(dir / (stem + ".svg"), plot(trips, report.summaries, spec, ctx));
  report.files = {dir / (stem + ".csv"), dir / (stem + "_summary.csv"), dir / (stem + ".svg")};
  report.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return report;
}

void require_runs(const AnalyticalOptions& o) {
  if (o.runs == 0 || o.level_runs == 0 || o.pairs == 0) throw std::invalid_argument("runs, level runs and pairs must be positive");
  if (o.out_dir.empty()) throw std::invalid_argument("an output directory is required");
}

}  // namespace

std::string strategy_label(const Strategy& s) {
  return std::string(to_string(s.routing)) + (s.signals == Signals::preemption ? " + preemption" : ", no preemption");
}

std::vector<ExperimentReport> run_graph_experiments(const AnalyticalGraph& g, const AnalyticalOptions& options) {
  require_runs(options);
  const GraphContext ctx{g.graph,
                         g.name.empty() ? "graph" : g.name,
                         [&g](NodeId v) { return g.name_of(v); },
                         g.graph.data().node_signalized,
                         g.source,
                         g.destination,
                         0.0,
                         2};
  const std::string pair = g.name_of(g.source) + " to " + g.name_of(g.destination);
  std::vector<ExperimentSpec> specs;
  ExperimentSpec levels = named_spec(g.name == "simple" ? "fig5" : g.name == "complex" ? "fig6" : "levels",
                        "travel time against congestion level, " + pair);
  levels.kind = Kind::levels;
  levels.levels_min = kLevelsMin;
  levels.placement = g.name == "simple" ? CongestionPlacement{2, 0} : CongestionPlacement{2, 2};
  levels.runs = options.level_runs;
  levels.plot = Plot::levels_minutes;
  specs.push_back(levels);
  if (g.name != "simple") {
    ExperimentSpec fig7 = named_spec("fig7", "random pairs, queue delay 0-7 min, signal delay 3 min");
    fig7.random_pairs = true;
    fig7.runs = options.runs;
    specs.push_back(fig7);
    ExperimentSpec fig8a = named_spec("fig8a", "signal delay 3 min, queue delay 0-7 min on the same links, " + pair);
    fig8a.fixed_sites = true;
    fig8a.runs = options.runs;
    fig8a.plot = Plot::bars_minutes;
    specs.push_back(fig8a);
    add_delay_variants(specs, fig8a, ", " + pair);
  }
  std::vector<ExperimentReport> reports;
  for (const ExperimentSpec& spec : specs) reports.push_back(run_experiment(ctx, spec, options));
  return reports;
}

std::vector<ExperimentReport> run_map_experiments(const maps::RoadGraph& graph, const std::string& name,
                                                  const AnalyticalOptions& options) {
  require_runs(options);
  const double diagonal = maps::distance_m(graph.min_corner(), graph.max_corner());
  const GraphContext ctx{graph,
                         name,
                         [&graph](NodeId v) { return std::to_string(graph.osm_node(v).v); },
                         options.map_signals == MapSignals::junctions ? junction_mask(graph) : graph.data().node_signalized,
                         NodeId{0},
                         NodeId{0},
                         std::min(1500.0, 0.3 * diagonal),
                         4};
  const CongestionPlacement placement{3, 3};
  std::vector<ExperimentSpec> specs;
  ExperimentSpec levels = named_spec("levels", "median increase against congestion level, random pairs");
  levels.kind = Kind::levels;
  levels.levels_min = kLevelsMin;
  levels.random_pairs = true;
  levels.placement = placement;
  levels.runs = std::max(1u, options.pairs / 4);
  levels.plot = Plot::levels_percent;
  specs.push_back(levels);
  ExperimentSpec fig7 = named_spec("fig7", "queue delay 0-7 min, signal delay 3 min");
  fig7.random_pairs = true;
  fig7.placement = placement;
  fig7.runs = options.pairs;
  fig7.plot = Plot::cdf_percent;
  specs.push_back(fig7);
  // Fig. 8a's protocol is Fig. 7's once every trip has its own pair and links; it is not repeated.
  add_delay_variants(specs, fig7, "");
  std::vector<ExperimentReport> reports;
  for (const ExperimentSpec& spec : specs) reports.push_back(run_experiment(ctx, spec, options));
  return reports;
}

std::string render_markdown(const std::vector<ExperimentReport>& reports) {
  std::string md;
  for (const ExperimentReport& r : reports) {
    md += fmt::format("### {} {}: {}\n\n", r.graph, r.experiment, r.title);
    const bool levels = !r.summaries.empty() && r.summaries.front().level_min >= 0.0;
    if (levels) {
      md += "Median travel time in minutes (median increase over the base in %), by queue delay per congested link.\n\n";
      md += "| level (min) |";
      for (const Strategy& s : kStrategies) md += " " + strategy_label(s) + " |";
      md += "\n|---|---|---|---|---|\n";
      for (std::size_t i = 0; i < r.summaries.size(); i += std::size(kStrategies)) {
        md += fmt::format("| {:g} |", r.summaries[i].level_min);
        for (std::size_t k = 0; k < std::size(kStrategies); ++k) {
          const StrategySummary& s = r.summaries[i + k];
          md += fmt::format(" {:.2f} ({:.0f}%) |", s.median_travel_s / kMinute, s.median_increase_pct);
        }
        md += "\n";
      }
    } else {
      md += "| strategy | trips | median travel (min) | median increase | mean increase |\n|---|---|---|---|---|\n";
      for (const StrategySummary& s : r.summaries) {
        md += fmt::format("| {} | {} | {:.2f} | {:.1f}% | {:.1f}% |\n", strategy_label(s.strategy), s.runs,
                          s.median_travel_s / kMinute, s.median_increase_pct, s.mean_increase_pct);
      }
    }
    md += "\n| dynamic routing | worse than static | better | same | rerouted trips | replans | route changes | replan time |\n"
          "|---|---|---|---|---|---|---|---|\n";
    // Totals over all levels for the dynamic rows.
    for (std::size_t k : {std::size_t{1}, std::size_t{3}}) {
      StrategySummary total;
      for (std::size_t i = k; i < r.summaries.size(); i += std::size(kStrategies)) {
        const StrategySummary& s = r.summaries[i];
        total.runs += s.runs;
        total.worse_than_static += s.worse_than_static;
        total.better_than_static += s.better_than_static;
        total.rerouted += s.rerouted;
        total.replans += s.replans;
        total.route_changes += s.route_changes;
        total.replan_wall_s += s.replan_wall_s;
      }
      md += fmt::format("| {} | {} | {} | {} | {} | {} | {} | {:.1f} ms |\n", strategy_label(kStrategies[k]),
                        total.worse_than_static, total.better_than_static,
                        total.runs - total.worse_than_static - total.better_than_static, total.rerouted, total.replans,
                        total.route_changes, total.replan_wall_s * 1000.0);
    }
    md += fmt::format("\nWall time of this experiment: {:.2f} s.\n\n", r.wall_s);
  }
  return md;
}

}  // namespace corridor::planner
