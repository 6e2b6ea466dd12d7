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

#include "sim/errors.hpp"
#include "sim/scenario_builder.hpp"
#include "sim/sumo_scenario.hpp"

namespace corridor::sim {
namespace {

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
  plan.net = build_scenario_net(o.scenario, std::filesystem::absolute(o.out_dir) / "scenario", {o.rebuild_net});
  plan.scenario = load_sumo_scenario(plan.net, o.ev_vclass);
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
    write_record(run.result_file, record);
  } catch (const std::exception& e) {
    // The failure is a record of this run too: a row of the tables, with its reason.
    try {
      write_record(run.result_file, failed_run(run.record, e.what()));
    } catch (const std::exception&) {
    }
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

// The plan beside the records (runs/matrix.json): every run's identity and record file, so that
// collecting knows the runs that left no record.
constexpr const char* kMatrixFile = "matrix.json";

void write_matrix(const Plan& plan, const std::filesystem::path& runs_dir) {
  nlohmann::json runs = nlohmann::json::array();
  for (const PlannedRun& r : plan.runs) {
    runs.push_back({{"file", std::filesystem::relative(r.result_file, runs_dir).string()}, {"identity", to_json_record(r.record)}});
  }
  std::filesystem::create_directories(runs_dir);
  write_text(runs_dir / kMatrixFile, nlohmann::json{{"runs", runs}}.dump(1) + "\n");
}

std::vector<PlannedRecord> planned_records(const Plan& plan) {
  std::vector<PlannedRecord> out;
  for (const PlannedRun& r : plan.runs) out.push_back({r.result_file, r.record});
  return out;
}

// The runs a matrix.json in `dir` planned; empty when there is none. Throws SimError for one that
// is not a plan.
std::vector<PlannedRecord> read_matrix(const std::filesystem::path& dir) {
  std::vector<PlannedRecord> out;
  const auto file = dir / kMatrixFile;
  std::ifstream in(file);
  if (!in) return out;
  try {
    const nlohmann::json j = nlohmann::json::parse(in);
    for (const auto& run : j.at("runs")) {
      out.push_back({dir / run.at("file").get<std::string>(), record_from_json(run.at("identity"), file.string())});
    }
  } catch (const nlohmann::json::exception& e) {
    throw SimError(file.string() + " is not an experiment plan: " + e.what());
  }
  return out;
}

}  // namespace

ExperimentTables run_sumo_experiment(const SumoExperimentOptions& o) {
  const Plan plan = plan_matrix(o);
  for (const PlannedRun& r : plan.runs) std::filesystem::create_directories(r.config.out_dir);
  write_matrix(plan, std::filesystem::absolute(o.out_dir) / "runs");
  // A record left over from an earlier matrix in the same directory is not this run's result.
  for (const PlannedRun& r : plan.runs) std::filesystem::remove(r.result_file);

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
  // Only this matrix's records; a run whose process died (SUMO can abort inside libsumo) left no
  // file and is a failed row.
  return write_experiment_tables(planned_records(plan), o.out_dir);
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
    if (o.ev_vclass != "emergency") args.insert(args.end(), {"--ev-vclass", o.ev_vclass});
    if (o.rebuild_net) args.emplace_back("--rebuild-net");
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
  write_matrix(plan, std::filesystem::absolute(o.out_dir) / "runs");
  return plan.runs.size();
}

ExperimentTables collect_sumo_experiment(const std::vector<std::filesystem::path>& dirs, const std::filesystem::path& out_dir) {
  std::vector<PlannedRecord> runs;
  std::set<std::filesystem::path> planned;
  for (const auto& d : dirs) {
    std::error_code ec;
    if (std::filesystem::is_regular_file(d, ec)) {
      runs.push_back({d, std::nullopt});
      continue;
    }
    if (!std::filesystem::is_directory(d, ec)) throw SimError("--collect: '" + d.string() + "' is not a directory");
    for (auto& r : read_matrix(d)) {
      planned.insert(r.file.lexically_normal());
      runs.push_back(std::move(r));
    }
    for (const auto& entry : std::filesystem::recursive_directory_iterator(d)) {
      if (!entry.is_regular_file() || !entry.path().filename().string().ends_with(".run.json")) continue;
      if (!planned.contains(entry.path().lexically_normal())) runs.push_back({entry.path(), std::nullopt});
    }
  }
  return write_experiment_tables(std::move(runs), out_dir);
}

ExperimentTables collect_run_files(std::vector<std::filesystem::path> files, const std::filesystem::path& out_dir) {
  std::vector<PlannedRecord> runs;
  for (auto& f : files) runs.push_back({std::move(f), std::nullopt});
  return write_experiment_tables(std::move(runs), out_dir);
}

}  // namespace corridor::sim
