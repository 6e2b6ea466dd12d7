#include "sim/sumo_experiment.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <set>

#include "planner/experiments/statistics.hpp"
#include "planner/experiments/svg_chart.hpp"
#include "sim/errors.hpp"
#include "sim/result_json.hpp"
#include "sim/scenario_builder.hpp"
#include "sim/sumo_scenario.hpp"

namespace corridor::sim {
namespace {

using planner::quantile;

struct PlannedRun {
  ClosedLoopConfig config;
  RunRecord record;  // identity; the result is filled by the run
  std::filesystem::path result_file;
};

struct Plan {
  ScenarioNet net;
  std::unique_ptr<SumoScenario> scenario;
  double begin_s = 0.0;
  std::vector<PlannedRun> runs;
};

void validate(const SumoExperimentOptions& o) {
  if (o.seeds == 0) throw SimError("the experiment needs at least one seed");
  if (o.routings.empty() || o.signals.empty()) throw SimError("the experiment needs at least one routing and one signal strategy");
  for (double v : o.volumes) {
    if (!(v > 0.0 && v <= 20000.0)) throw SimError("volumes must be in (0, 20000] vehicles/hour");
  }
  for (double s : o.demand_scales) {
    if (!(s > 0.0 && s <= 20.0)) throw SimError("demand scales must be in (0, 20]");
  }
  if (o.out_dir.empty()) throw SimError("the experiment needs an output directory");
}

std::string demand_label(const RunRecord& r) {
  return r.volume > 0.0 ? fmt::format("v{:g}", r.volume) : fmt::format("x{:g}", r.demand_scale);
}

Plan plan_matrix(const SumoExperimentOptions& o) {
  validate(o);
  Plan plan;
  plan.net = build_scenario_net(o.scenario, std::filesystem::absolute(o.out_dir) / "scenario");
  plan.scenario = load_sumo_scenario(plan.net);
  const auto& config = plan.net.config;
  if (config && o.demand_scales.empty()) throw SimError("a .sumocfg scenario needs at least one demand scale");
  if (!config && o.volumes.empty()) throw SimError("a generated scenario needs at least one volume");
  if (config && o.inject_on_route) throw SimError("--inject-on-route is for generated scenarios; a .sumocfg brings its own demand");
  if (o.inject_on_route && !(o.background_vph > 0.0 && o.background_vph <= 20000.0)) {
    throw SimError("--background-vph must be in (0, 20000] vehicles/hour");
  }
  plan.begin_s = config ? config->begin_s : 0.0;
  const double end_after_begin = o.end_s ? *o.end_s : (config && config->end_s ? *config->end_s - plan.begin_s : 2400.0);
  if (!(end_after_begin > o.ev_depart_s && o.ev_depart_s >= 0.0)) {
    throw SimError(fmt::format("the EV departs {:g} s after the scenario's begin, but the runs end {:g} s after it",
                               o.ev_depart_s, end_after_begin));
  }
  std::vector<std::pair<double, double>> demands;  // volume, scale
  if (config) {
    for (double s : o.demand_scales) demands.emplace_back(0.0, s);
  } else {
    for (double v : o.volumes) demands.emplace_back(v, 1.0);
  }
  const auto runs_dir = std::filesystem::absolute(o.out_dir) / "runs";
  for (const auto& [volume, scale] : demands) {
    for (std::uint64_t seed = o.first_seed; seed < o.first_seed + o.seeds; ++seed) {
      ClosedLoopConfig base;
      std::tie(base.ev_from, base.ev_to) = pick_ev_trip(*plan.scenario, seed);
      if (!config) {
        base.background_routes =
            build_background_demand(plan.net, {o.inject_on_route ? o.background_vph : volume, o.demand_end_s, seed});
      }
      if (o.inject_on_route) base.inject_on_route_vph = volume;
      base.demand_scale = scale;
      base.ev_depart_s = plan.begin_s + o.ev_depart_s;
      base.end_s = plan.begin_s + end_after_begin;
      base.seed = seed;
      base.congestion_period_s = o.congestion_period_s;
      base.incidents = o.incidents;
      base.backend = o.backend;
      base.vicinity = o.vicinity;
      if (o.evs > 1) {
        base.more_evs = conflicting_ev_trips(*plan.scenario, {base.ev_from, base.ev_to, base.ev_depart_s, 1}, o.evs - 1, seed,
                                             base.ev_vmax_kmh);
        base.first_priority = static_cast<int>(o.evs);
      }
      RunRecord identity;
      identity.vicinity = o.vicinity;
      identity.inject_on_route = o.inject_on_route;
      identity.evs = o.evs;
      identity.scenario = plan.net.name;
      identity.volume = volume;
      identity.demand_scale = scale;
      identity.seed = seed;
      identity.ev_from = base.ev_from;
      identity.ev_to = base.ev_to;
      identity.ev_depart_s = base.ev_depart_s;
      base.out_dir = runs_dir / fmt::format("{}_s{}", demand_label(identity), seed);

      ClosedLoopConfig baseline = base;
      baseline.with_ev = false;
      baseline.run_name = "baseline";
      RunRecord baseline_identity = identity;
      baseline_identity.with_ev = false;
      plan.runs.push_back({baseline, baseline_identity, base.out_dir / "baseline.run.json"});
      for (EvRouting r : o.routings) {
        for (EvSignals s : o.signals) {
          ClosedLoopConfig c = base;
          c.routing = r;
          c.signals = s;
          // corridor+bluelight -> corridor_bluelight: a file name without a shell metacharacter.
          std::string name = fmt::format("{}_{}", to_string(r), to_string(s));
          std::replace(name.begin(), name.end(), '+', '_');
          c.run_name = name;
          RunRecord id = identity;
          id.routing = r;
          id.signals = s;
          plan.runs.push_back({c, id, base.out_dir / (name + ".run.json")});
        }
      }
    }
  }
  return plan;
}

void write_text(const std::filesystem::path& file, const std::string& text) {
  std::ofstream out(file, std::ios::trunc | std::ios::binary);
  out << text;
  if (!out) throw SimError("cannot write " + file.string());
}

// Each run in a forked child: libtraci keeps one global connection table, and a SUMO that dies
// takes only its own run down. The child leaves its record, or the error, in the result file.
pid_t start_run(const SumoScenario& scenario, const PlannedRun& run) {
  const pid_t pid = fork();
  if (pid < 0) throw SimError("fork failed");
  if (pid > 0) return pid;
  // libsumo prints SUMO's messages on this process's stdout and stderr: into the run's directory.
  const auto console = run.config.out_dir / (run.config.run_name + ".console.log");
  if (FILE* f = std::fopen(console.c_str(), "w")) {
    dup2(fileno(f), STDOUT_FILENO);
    dup2(fileno(f), STDERR_FILENO);
    std::fclose(f);
  }
  int code = 0;
  try {
    RunRecord record = run.record;
    record.result = run_closed_loop(scenario, run.config);
    write_text(run.result_file, to_json_record(record).dump());
  } catch (const std::exception& e) {
    std::ofstream(run.result_file, std::ios::trunc) << nlohmann::json{{"error", e.what()}}.dump();
    code = 1;
  }
  std::fflush(nullptr);
  _exit(code);
}

std::string shell_quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

std::string label(EvRouting r, EvSignals s) { return fmt::format("{} / {}", to_string(r), to_string(s)); }

}  // namespace

nlohmann::json to_json_record(const RunRecord& r) {
  nlohmann::json j = r.result;
  j["scenario"] = r.scenario;
  j["with_ev"] = r.with_ev;
  j["routing"] = to_string(r.routing);
  j["signals"] = to_string(r.signals);
  j["volume"] = r.volume;
  j["demand_scale"] = r.demand_scale;
  j["seed"] = r.seed;
  j["ev_from"] = r.ev_from;
  j["ev_to"] = r.ev_to;
  j["ev_depart_s"] = r.ev_depart_s;
  j["vicinity"] = r.vicinity;
  j["inject_on_route"] = r.inject_on_route;
  j["ev_count"] = r.evs;
  return j;
}

RunRecord record_from_json(const nlohmann::json& j, const std::string& source) {
  if (!j.is_object()) throw SimError(source + ": not a run record");
  if (j.contains("error")) throw SimError(source + ": the run failed: " + j.value("error", std::string{}));
  try {
    RunRecord r;
    r.scenario = j.at("scenario").get<std::string>();
    r.with_ev = j.at("with_ev").get<bool>();
    const auto routing = parse_ev_routing(j.at("routing").get<std::string>());
    if (!routing) throw SimError("unknown routing '" + j.at("routing").get<std::string>() + "'");
    r.routing = *routing;
    const auto signals = parse_ev_signals(j.at("signals").get<std::string>());
    if (!signals) throw SimError("unknown signals '" + j.at("signals").get<std::string>() + "'");
    r.signals = *signals;
    r.volume = j.at("volume").get<double>();
    r.demand_scale = j.at("demand_scale").get<double>();
    r.seed = j.at("seed").get<std::uint64_t>();
    r.ev_from = j.value("ev_from", std::string{});
    r.ev_to = j.value("ev_to", std::string{});
    r.ev_depart_s = j.at("ev_depart_s").get<double>();
    r.vicinity = j.value("vicinity", true);
    r.inject_on_route = j.value("inject_on_route", false);
    r.evs = j.value("ev_count", std::uint32_t{1});
    r.result = j.get<ClosedLoopResult>();
    return r;
  } catch (const nlohmann::json::exception& e) {
    throw SimError(source + ": not a run record (" + e.what() + ")");
  } catch (const SimError& e) {
    throw SimError(source + ": " + e.what());
  }
}

double ExperimentRow::others_delay_rel() const {
  return baseline_time_loss_s > 0.0 ? run.result.others_mean_time_loss_s / baseline_time_loss_s - 1.0 : 0.0;
}

double ExperimentRow::ev_time_s() const {
  return run.result.ev_arrived ? run.result.ev_travel_time_s : std::max(0.0, run.result.end_time_s - run.ev_depart_s);
}

std::vector<ExperimentRow> run_sumo_experiment(const SumoExperimentOptions& o) {
  const Plan plan = plan_matrix(o);
  for (const PlannedRun& r : plan.runs) std::filesystem::create_directories(r.config.out_dir);

  // Two at a time (one per core), in forked children.
  std::set<pid_t> running;
  std::size_t next = 0, done = 0;
  while (done < plan.runs.size()) {
    while (next < plan.runs.size() && running.size() < std::max(1u, o.parallel)) {
      running.insert(start_run(*plan.scenario, plan.runs[next]));
      ++next;
    }
    int status = 0;
    const pid_t pid = waitpid(-1, &status, 0);
    if (pid < 0) throw SimError("waiting for a run failed");
    if (running.erase(pid) > 0) {
      ++done;
      if (done % 10 == 0 || done == plan.runs.size()) {
        spdlog::info("event=sumo_experiment_progress done={} of={}", done, plan.runs.size());
      }
    }
  }
  // Only this matrix's records: an output directory reused for another matrix keeps its old files.
  std::vector<std::filesystem::path> files;
  for (const PlannedRun& r : plan.runs) files.push_back(r.result_file);
  // A run whose process died (SUMO can abort inside libsumo) left no file: listed, not fatal.
  return collect_run_files(files, o.out_dir);
}

std::size_t emit_sumo_jobs(const SumoExperimentOptions& o, const std::filesystem::path& jobs_file,
                           const std::filesystem::path& corridor_binary) {
  const Plan plan = plan_matrix(o);
  const std::string scenario = plan.net.config ? plan.net.config->file.string() : plan.net.net.string();
  std::string lines;
  for (const PlannedRun& run : plan.runs) {
    const ClosedLoopConfig& c = run.config;
    std::filesystem::create_directories(c.out_dir);
    std::vector<std::string> args{corridor_binary.string(), "sim",
                                  "--scenario", scenario,
                                  "--work-dir", c.out_dir.string(),
                                  "--run-name", c.run_name,
                                  "--routing", to_string(c.routing),
                                  "--signals", to_string(c.signals),
                                  "--seed", std::to_string(c.seed),
                                  "--ev-from", c.ev_from,
                                  "--ev-to", c.ev_to,
                                  "--ev-depart-s", fmt::format("{:g}", c.ev_depart_s - plan.begin_s),
                                  "--end-s", fmt::format("{:g}", c.end_s - plan.begin_s),
                                  "--congestion-period-s", fmt::format("{:g}", c.congestion_period_s),
                                  "--incidents", std::to_string(c.incidents),
                                  "--evs", std::to_string(c.with_ev ? run.record.evs : 1u),
                                  "--result", run.result_file.string()};
    if (!c.vicinity) args.emplace_back("--route-only");
    if (plan.net.config) {
      args.insert(args.end(), {"--demand-scale", fmt::format("{:g}", c.demand_scale)});
    } else {
      args.insert(args.end(), {"--volume", fmt::format("{:g}", o.inject_on_route ? o.background_vph : run.record.volume),
                               "--background-routes", c.background_routes.string()});
      if (o.inject_on_route) args.insert(args.end(), {"--inject-vph", fmt::format("{:g}", run.record.volume)});
    }
    if (!c.with_ev) args.emplace_back("--no-ev");
    if (c.backend == SumoBackend::libsumo) args.emplace_back("--libsumo");
    std::string line;
    for (const auto& a : args) line += (line.empty() ? "" : " ") + shell_quote(a);
    // The record is all a run must leave; its JSON on stdout would only interleave under parallel.
    lines += line + " > /dev/null\n";
  }
  if (jobs_file.has_parent_path()) std::filesystem::create_directories(jobs_file.parent_path());
  write_text(jobs_file, lines);
  return plan.runs.size();
}

std::vector<ExperimentRow> collect_sumo_experiment(const std::vector<std::filesystem::path>& dirs,
                                                   const std::filesystem::path& out_dir) {
  std::vector<std::filesystem::path> files;
  for (const auto& d : dirs) {
    std::error_code ec;
    if (std::filesystem::is_regular_file(d, ec)) {
      files.push_back(d);
      continue;
    }
    if (!std::filesystem::is_directory(d, ec)) throw SimError("--collect: '" + d.string() + "' is not a directory");
    for (const auto& entry : std::filesystem::recursive_directory_iterator(d)) {
      if (entry.is_regular_file() && entry.path().filename().string().ends_with(".run.json")) files.push_back(entry.path());
    }
  }
  return collect_run_files(files, out_dir);
}

std::vector<ExperimentRow> collect_run_files(std::vector<std::filesystem::path> files, const std::filesystem::path& out_dir) {
  std::sort(files.begin(), files.end());
  files.erase(std::unique(files.begin(), files.end()), files.end());

  std::vector<RunRecord> records;
  std::vector<std::string> failed;
  for (const auto& f : files) {
    std::ifstream in(f);
    nlohmann::json j;
    try {
      if (!in) throw SimError(f.string() + ": no result (the run ended without one; see its .console.log and .sumo.log)");
      in >> j;
      records.push_back(record_from_json(j, f.string()));
    } catch (const nlohmann::json::exception&) {
      failed.push_back(f.string() + ": no result (the run did not finish)");
    } catch (const SimError& e) {
      failed.push_back(e.what());
    }
  }
  for (const auto& f : failed) spdlog::warn("event=sumo_run_failed detail=\"{}\"", f);
  if (records.empty()) {
    throw SimError("no run records (*.run.json) to collect" + (failed.empty() ? std::string{} : ": " + failed.front()));
  }
  const std::string scenario = records.front().scenario;
  for (const RunRecord& r : records) {
    if (r.scenario != scenario) throw SimError("the records mix scenarios '" + scenario + "' and '" + r.scenario + "'");
    if (r.with_ev && (r.vicinity != records.front().vicinity || r.evs != records.front().evs)) {
      throw SimError("the records mix vicinity-aware and route-only preemption, or numbers of EVs: collect them apart");
    }
  }
  const bool vicinity = std::all_of(records.begin(), records.end(), [](const RunRecord& r) { return r.vicinity; });
  std::uint32_t evs = 1;
  for (const RunRecord& r : records) evs = std::max(evs, r.evs);

  using Key = std::tuple<double, double, std::uint64_t>;  // volume, scale, seed
  std::map<Key, double> baseline;
  for (const RunRecord& r : records) {
    if (!r.with_ev) baseline[{r.volume, r.demand_scale, r.seed}] = r.result.others_mean_time_loss_s;
  }
  std::vector<ExperimentRow> rows;
  for (const RunRecord& r : records) {
    if (!r.with_ev) continue;
    const auto it = baseline.find({r.volume, r.demand_scale, r.seed});
    if (it == baseline.end()) {
      failed.push_back(fmt::format("{} / {} at {} seed {}: no baseline run without the EV", to_string(r.routing),
                                   to_string(r.signals), demand_label(r), r.seed));
      continue;
    }
    rows.push_back({r, it->second});
  }
  std::sort(rows.begin(), rows.end(), [](const ExperimentRow& a, const ExperimentRow& b) {
    return std::tuple(a.run.volume, a.run.demand_scale, a.run.seed, a.run.routing, a.run.signals) <
           std::tuple(b.run.volume, b.run.demand_scale, b.run.seed, b.run.routing, b.run.signals);
  });

  std::string csv =
      "routing,signals,volume,seed,ev_travel_time_s,ev_stops,ev_wait_s,preempted_signals,others_delay_rel,collisions,"
      "teleports,ev_arrived,ev_time_loss_s,route_changes,replans,lights_taken_over,lights_back_on_program,"
      "safety_violations,others,others_mean_time_loss_s,baseline_time_loss_s,demand_scale,scenario,ev_from,ev_to,"
      "vicinity,evs,evs_arrived,evs_travel_time_mean_s,deferrals\n";
  for (const ExperimentRow& row : rows) {
    const RunRecord& r = row.run;
    std::size_t evs_arrived = 0;
    double evs_time = 0.0;
    for (const EvOutcome& e : r.result.evs) {
      evs_arrived += e.arrived ? 1 : 0;
      evs_time += e.arrived ? e.travel_time_s : 0.0;
    }
    csv += fmt::format("{},{},{:g},{},{:.1f},{},{:.1f},{},{:.4f},{},{},{},{:.1f},{},{},{},{},{},{},{:.3f},{:.3f},{:g},{},{},{},"
                       "{},{},{},{:.1f},{}\n",
                       to_string(r.routing), to_string(r.signals), r.volume, r.seed, r.result.ev_travel_time_s,
                       r.result.ev_stops, r.result.ev_wait_s, r.result.preempted_signals, row.others_delay_rel(),
                       r.result.collisions, r.result.teleports, r.result.ev_arrived ? 1 : 0, r.result.ev_time_loss_s,
                       r.result.route_changes, r.result.replans, r.result.lights_taken_over,
                       r.result.lights_back_on_program, r.result.safety_violations.size(), r.result.others,
                       r.result.others_mean_time_loss_s, row.baseline_time_loss_s, r.demand_scale, r.scenario,
                       r.ev_from, r.ev_to, r.vicinity ? 1 : 0, r.evs, evs_arrived,
                       evs_arrived > 0 ? evs_time / static_cast<double>(evs_arrived) : 0.0, r.result.deferrals);
  }
  std::filesystem::create_directories(out_dir);
  write_text(out_dir / "sumo_runs.csv", csv);

  // The demand levels, routings and strategies present, in order.
  std::set<std::pair<double, double>> demand_set;
  std::set<EvRouting> routing_set;
  std::set<EvSignals> signal_set;
  std::set<std::uint64_t> seeds;
  for (const ExperimentRow& row : rows) {
    demand_set.insert({row.run.volume, row.run.demand_scale});
    routing_set.insert(row.run.routing);
    signal_set.insert(row.run.signals);
    seeds.insert(row.run.seed);
  }
  const std::vector<std::pair<double, double>> demands(demand_set.begin(), demand_set.end());
  const bool scaled = !demands.empty() && demands.front().first == 0.0;
  const auto demand_name = [&](const std::pair<double, double>& d) {
    return scaled ? fmt::format("demand x{:g}", d.second) : fmt::format("{:g} veh/h", d.first);
  };

  struct Cell {
    std::vector<double> tt, stops, rel;
    int arrived = 0, collisions = 0, teleports = 0;
    std::size_t violations = 0;
  };
  std::map<std::tuple<EvRouting, EvSignals, std::pair<double, double>>, Cell> cells;
  for (const ExperimentRow& row : rows) {
    Cell& c = cells[{row.run.routing, row.run.signals, {row.run.volume, row.run.demand_scale}}];
    c.tt.push_back(row.ev_time_s());
    c.stops.push_back(row.run.result.ev_stops);
    c.rel.push_back(row.others_delay_rel());
    c.arrived += row.run.result.ev_arrived ? 1 : 0;
    c.collisions += row.run.result.collisions;
    c.teleports += row.run.result.teleports;
    c.violations += row.run.result.safety_violations.size();
  }

  std::string summary =
      "routing,signals,volume,runs,arrived,ev_travel_time_median_s,ev_travel_time_q1_s,ev_travel_time_q3_s,"
      "ev_stops_median,others_delay_rel_median,others_delay_rel_q1,others_delay_rel_q3,collisions,teleports,"
      "safety_violations,demand_scale\n";
  std::string md = fmt::format(
      "Scenario `{}`, {} seeds per demand level, {} preemption{}. EV travel time: median [IQR] in s (an EV that did not arrive counts "
      "with the time it was still driving). Others: median change of the other vehicles' mean time loss against the "
      "same run without the EV.\n\n| routing / signals |",
      scenario, seeds.size(), vicinity ? "vicinity-aware" : "route-only",
      evs > 1 ? fmt::format(", {} EVs per run (the first EV's figures; every EV's in sumo_runs.csv)", evs) : std::string{});
  for (const auto& d : demands) md += " " + demand_name(d) + " |";
  md += "\n|---|";
  for (std::size_t i = 0; i < demands.size(); ++i) md += "---|";
  md += "\n";
  std::vector<planner::ChartSeries> travel, delay;
  for (EvRouting r : routing_set) {
    for (EvSignals s : signal_set) {
      planner::ChartSeries ts{label(r, s), {}, {}}, ds{label(r, s), {}, {}};
      std::string line = "| " + label(r, s) + " |";
      for (const auto& d : demands) {
        const auto it = cells.find({r, s, d});
        if (it == cells.end()) {
          line += " – |";
          continue;
        }
        const Cell& c = it->second;
        summary += fmt::format("{},{},{:g},{},{},{:.1f},{:.1f},{:.1f},{:.1f},{:.4f},{:.4f},{:.4f},{},{},{},{:g}\n",
                               to_string(r), to_string(s), d.first, c.tt.size(), c.arrived, quantile(c.tt, 0.5),
                               quantile(c.tt, 0.25), quantile(c.tt, 0.75), quantile(c.stops, 0.5), quantile(c.rel, 0.5),
                               quantile(c.rel, 0.25), quantile(c.rel, 0.75), c.collisions, c.teleports, c.violations,
                               d.second);
        line += fmt::format(" {:.0f} [{:.0f}–{:.0f}], others {:+.1f}%{} |", quantile(c.tt, 0.5), quantile(c.tt, 0.25),
                            quantile(c.tt, 0.75), 100.0 * quantile(c.rel, 0.5),
                            c.arrived == static_cast<int>(c.tt.size()) ? "" : fmt::format(", {} of {} arrived", c.arrived, c.tt.size()));
        ts.x.push_back(scaled ? d.second : d.first);
        ts.y.push_back(quantile(c.tt, 0.5));
        ds.x.push_back(scaled ? d.second : d.first);
        ds.y.push_back(100.0 * quantile(c.rel, 0.5));
      }
      md += line + "\n";
      travel.push_back(std::move(ts));
      delay.push_back(std::move(ds));
    }
  }

  // The comparison: the best Corridor strategy against static/none and against bluelight alone.
  md += "\nBest Corridor strategy per demand level (lowest median EV travel time among the corridor strategies), "
        "against a static route with no help (static / none) and with SUMO's bluelight alone (static / bluelight):\n\n";
  for (const auto& d : demands) {
    const auto median = [&](EvRouting r, EvSignals s) {
      const auto it = cells.find({r, s, d});
      return it == cells.end() ? std::nan("") : quantile(it->second.tt, 0.5);
    };
    std::optional<std::pair<EvRouting, EvSignals>> best;
    for (EvRouting r : routing_set) {
      for (EvSignals s : signal_set) {
        if (!preempts(s) || std::isnan(median(r, s))) continue;
        if (!best || median(r, s) < median(best->first, best->second)) best = std::pair(r, s);
      }
    }
    if (!best) continue;
    const double b = median(best->first, best->second);
    const double none = median(EvRouting::static_route, EvSignals::none);
    const double blue = median(EvRouting::static_route, EvSignals::bluelight);
    const Cell& c = cells.at({best->first, best->second, d});
    // A matrix without a baseline strategy (say, only the corridor ones) says so instead of NaN.
    const auto against = [&](double base, const char* name) {
      return std::isnan(base) ? fmt::format("no {} run in this matrix", name)
                              : fmt::format("{:+.1f}% against {} ({:.0f} s)", 100.0 * (b / base - 1.0), name, base);
    };
    md += fmt::format("- {}: {} {:.0f} s; {}, {}; others' delay {:+.1f}% [IQR {:+.1f}, {:+.1f}]; {} of {} EVs arrived; "
                      "{} collisions, {} safety violations\n",
                      demand_name(d), label(best->first, best->second), b, against(none, "static / none"),
                      against(blue, "static / bluelight"), 100.0 * quantile(c.rel, 0.5), 100.0 * quantile(c.rel, 0.25),
                      100.0 * quantile(c.rel, 0.75), c.arrived, c.tt.size(), c.collisions, c.violations);
  }
  if (!failed.empty()) {
    md += fmt::format("\n{} run(s) left out:\n\n", failed.size());
    for (const auto& f : failed) md += "- " + f + "\n";
  }
  write_text(out_dir / "sumo_summary.csv", summary);
  write_text(out_dir / "sumo_summary.md", md);
  const bool injected = std::any_of(rows.begin(), rows.end(), [](const ExperimentRow& r) { return r.run.inject_on_route; });
  const std::string x_label = scaled     ? "demand scale (x the scenario's own demand)"
                              : injected ? "volume injected on the EV's static route (vehicles/hour)"
                                         : "background volume (vehicles/hour)";
  write_text(out_dir / "sumo_travel_time.svg",
             planner::render_line_chart({fmt::format("{}: EV travel time against demand", scenario), x_label,
                                         "median EV travel time (s)"},
                                        travel));
  write_text(out_dir / "sumo_others_delay.svg",
             planner::render_line_chart({fmt::format("{}: other vehicles' delay against demand", scenario), x_label,
                                         "median change of mean time loss (%)"},
                                        delay, false));
  return rows;
}

}  // namespace corridor::sim
