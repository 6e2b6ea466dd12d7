#include "sim/sumo_experiment.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>

#include "planner/experiments/statistics.hpp"
#include "planner/experiments/svg_chart.hpp"
#include "sim/errors.hpp"
#include "sim/result_json.hpp"
#include "sim/scenario_builder.hpp"
#include "sim/sumo_scenario.hpp"

namespace corridor::sim {
namespace {

using planner::quantile;

constexpr EvRouting kRoutings[] = {EvRouting::static_route, EvRouting::dynamic_route};
constexpr EvSignals kSignals[] = {EvSignals::none, EvSignals::bluelight, EvSignals::corridor};

struct Job {
  ClosedLoopConfig config;
  double volume;
  std::filesystem::path result_file;
  pid_t pid = -1;
};

// Each run in a forked child: libtraci keeps one global connection table, and a SUMO that dies
// takes only its own run down.
pid_t start_job(const SumoScenario& scenario, const Job& job) {
  const pid_t pid = fork();
  if (pid < 0) throw SimError("fork failed");
  if (pid > 0) return pid;
  int code = 0;
  try {
    const ClosedLoopResult r = run_closed_loop(scenario, job.config);
    std::ofstream(job.result_file, std::ios::trunc) << nlohmann::json(r).dump();
  } catch (const std::exception& e) {
    std::ofstream(job.result_file, std::ios::trunc) << nlohmann::json{{"error", e.what()}}.dump();
    code = 1;
  }
  std::fflush(nullptr);
  _exit(code);
}

ClosedLoopResult finish_job(const Job& job) {
  std::ifstream in(job.result_file);
  nlohmann::json j;
  try {
    in >> j;
  } catch (const std::exception&) {
    throw SimError("run " + job.config.run_name + " ended without a result; see " + job.config.out_dir.string());
  }
  if (j.contains("error")) throw SimError("run " + job.config.run_name + " failed: " + j["error"].get<std::string>());
  return j.get<ClosedLoopResult>();
}

std::string label(EvRouting r, EvSignals s) { return fmt::format("{} / {}", to_string(r), to_string(s)); }

void write_text(const std::filesystem::path& file, const std::string& text) {
  std::ofstream out(file, std::ios::trunc | std::ios::binary);
  out << text;
  if (!out) throw SimError("cannot write " + file.string());
}

}  // namespace

double ExperimentRow::others_delay_rel() const {
  return baseline_time_loss_s > 0.0 ? result.others_mean_time_loss_s / baseline_time_loss_s - 1.0 : 0.0;
}

std::vector<ExperimentRow> run_sumo_experiment(const SumoExperimentOptions& o) {
  if (o.volumes.empty() || o.seeds == 0) throw SimError("the experiment needs at least one volume and one seed");
  for (double v : o.volumes) {
    if (!(v > 0.0 && v <= 20000.0)) throw SimError("volumes must be in (0, 20000] vehicles/hour");
  }
  const auto scenario_dir = o.out_dir / "scenario";
  const ScenarioNet net = build_scenario_net(o.scenario, scenario_dir);
  const auto scenario = load_sumo_scenario(net.name, net.dir, net.net);

  std::vector<Job> jobs;
  for (double volume : o.volumes) {
    for (std::uint64_t seed = o.first_seed; seed < o.first_seed + o.seeds; ++seed) {
      ClosedLoopConfig base;
      std::tie(base.ev_from, base.ev_to) = pick_ev_trip(*scenario, seed);
      base.background_routes = build_background_demand(net, {volume, o.demand_end_s, seed});
      base.ev_depart_s = o.ev_depart_s;
      base.end_s = o.end_s;
      base.seed = seed;
      base.congestion_period_s = o.congestion_period_s;
      base.incidents = o.incidents;
      base.backend = o.backend;
      base.out_dir = o.out_dir / "runs" / fmt::format("v{:g}_s{}", volume, seed);
      ClosedLoopConfig baseline = base;
      baseline.with_ev = false;
      baseline.run_name = "baseline";
      jobs.push_back({baseline, volume, base.out_dir / "baseline.json"});
      for (EvRouting r : kRoutings) {
        for (EvSignals s : kSignals) {
          ClosedLoopConfig c = base;
          c.routing = r;
          c.signals = s;
          c.run_name = fmt::format("{}_{}", to_string(r), to_string(s));
          jobs.push_back({c, volume, base.out_dir / (c.run_name + ".json")});
        }
      }
    }
  }
  for (const Job& j : jobs) std::filesystem::create_directories(j.config.out_dir);

  // Two at a time (one per core), in forked children.
  std::map<pid_t, std::size_t> running;
  std::size_t next = 0;
  std::size_t done = 0;
  while (done < jobs.size()) {
    while (next < jobs.size() && running.size() < std::max(1u, o.parallel)) {
      jobs[next].pid = start_job(*scenario, jobs[next]);
      running[jobs[next].pid] = next;
      ++next;
    }
    int status = 0;
    const pid_t pid = waitpid(-1, &status, 0);
    if (pid < 0) throw SimError("waiting for a run failed");
    if (running.erase(pid) > 0) {
      ++done;
      if (done % 10 == 0 || done == jobs.size()) spdlog::info("event=sumo_experiment_progress done={} of={}", done, jobs.size());
    }
  }

  std::map<std::pair<double, std::uint64_t>, double> baseline;
  std::vector<ExperimentRow> rows;
  for (const Job& j : jobs) {
    const ClosedLoopResult r = finish_job(j);
    if (!j.config.with_ev) {
      baseline[{j.volume, j.config.seed}] = r.others_mean_time_loss_s;
      continue;
    }
    rows.push_back({j.config.routing, j.config.signals, j.volume, j.config.seed, r, 0.0});
  }
  for (ExperimentRow& row : rows) row.baseline_time_loss_s = baseline.at({row.volume, row.seed});

  std::string csv =
      "routing,signals,volume,seed,ev_travel_time_s,ev_stops,ev_wait_s,preempted_signals,others_delay_rel,collisions,"
      "teleports,ev_arrived,ev_time_loss_s,route_changes,replans,lights_taken_over,lights_back_on_program,"
      "safety_violations,others,others_mean_time_loss_s,baseline_time_loss_s\n";
  for (const ExperimentRow& r : rows) {
    csv += fmt::format("{},{},{:g},{},{:.1f},{},{:.1f},{},{:.4f},{},{},{},{:.1f},{},{},{},{},{},{},{:.3f},{:.3f}\n",
                       to_string(r.routing), to_string(r.signals), r.volume, r.seed, r.result.ev_travel_time_s,
                       r.result.ev_stops, r.result.ev_wait_s, r.result.preempted_signals, r.others_delay_rel(),
                       r.result.collisions, r.result.teleports, r.result.ev_arrived ? 1 : 0, r.result.ev_time_loss_s,
                       r.result.route_changes, r.result.replans, r.result.lights_taken_over,
                       r.result.lights_back_on_program, r.result.safety_violations.size(), r.result.others,
                       r.result.others_mean_time_loss_s, r.baseline_time_loss_s);
  }
  std::filesystem::create_directories(o.out_dir);
  write_text(o.out_dir / "sumo_runs.csv", csv);

  // Summary: median and IQR per combination and volume.
  std::string summary =
      "routing,signals,volume,runs,arrived,ev_travel_time_median_s,ev_travel_time_q1_s,ev_travel_time_q3_s,"
      "ev_stops_median,others_delay_rel_median,others_delay_rel_q1,others_delay_rel_q3,collisions,teleports,"
      "safety_violations\n";
  std::string md = fmt::format("Scenario `{}`, {} seeds per volume. EV travel time: median [IQR] in s. Others' delay: "
                               "median change of the other vehicles' mean time loss against the same run without the EV.\n\n"
                               "| routing / signals |",
                               net.name, o.seeds);
  for (double v : o.volumes) md += fmt::format(" {:g} veh/h |", v);
  md += "\n|---|";
  for (std::size_t i = 0; i < o.volumes.size(); ++i) md += "---|";
  md += "\n";
  std::vector<planner::ChartSeries> travel, delay;
  for (EvRouting r : kRoutings) {
    for (EvSignals s : kSignals) {
      planner::ChartSeries ts{label(r, s), {}, {}}, ds{label(r, s), {}, {}};
      std::string line = "| " + label(r, s) + " |";
      for (double v : o.volumes) {
        std::vector<double> tt, stops, rel;
        int arrived = 0, collisions = 0, teleports = 0;
        std::size_t violations = 0;
        for (const ExperimentRow& row : rows) {
          if (row.routing != r || row.signals != s || row.volume != v) continue;
          tt.push_back(row.result.ev_arrived ? row.result.ev_travel_time_s : o.end_s);
          stops.push_back(row.result.ev_stops);
          rel.push_back(row.others_delay_rel());
          arrived += row.result.ev_arrived ? 1 : 0;
          collisions += row.result.collisions;
          teleports += row.result.teleports;
          violations += row.result.safety_violations.size();
        }
        summary += fmt::format("{},{},{:g},{},{},{:.1f},{:.1f},{:.1f},{:.1f},{:.4f},{:.4f},{:.4f},{},{},{}\n", to_string(r),
                               to_string(s), v, tt.size(), arrived, quantile(tt, 0.5), quantile(tt, 0.25),
                               quantile(tt, 0.75), quantile(stops, 0.5), quantile(rel, 0.5), quantile(rel, 0.25),
                               quantile(rel, 0.75), collisions, teleports, violations);
        line += fmt::format(" {:.0f} [{:.0f}-{:.0f}], others {:+.1f}% |", quantile(tt, 0.5), quantile(tt, 0.25),
                            quantile(tt, 0.75), 100.0 * quantile(rel, 0.5));
        ts.x.push_back(v);
        ts.y.push_back(quantile(tt, 0.5));
        ds.x.push_back(v);
        ds.y.push_back(100.0 * quantile(rel, 0.5));
      }
      md += line + "\n";
      travel.push_back(std::move(ts));
      delay.push_back(std::move(ds));
    }
  }
  write_text(o.out_dir / "sumo_summary.csv", summary);
  write_text(o.out_dir / "sumo_summary.md", md);
  write_text(o.out_dir / "sumo_travel_time.svg",
             planner::render_line_chart({fmt::format("{}: EV travel time against volume", net.name),
                                         "background volume (vehicles/hour)", "median EV travel time (s)"},
                                        travel));
  write_text(o.out_dir / "sumo_others_delay.svg",
             planner::render_line_chart({fmt::format("{}: other vehicles' delay against volume", net.name),
                                         "background volume (vehicles/hour)", "median change of mean time loss (%)"},
                                        delay, false));
  return rows;
}

}  // namespace corridor::sim
