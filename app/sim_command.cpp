#include "app/sim_command.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <optional>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <memory>

#include "app/cli_error.hpp"
#include "app/listen_address.hpp"
#include "maps/sumo_vehicle_class.hpp"
#include "sim/closed_loop.hpp"
#include "sim/run_record.hpp"
#include "sim/sumo_experiment.hpp"
#include "sim/scenario_builder.hpp"
#include "sim/sumo_scenario.hpp"

namespace corridor::app {
namespace {

struct SimOptions {
  std::string scenario = "grid";
  std::string work_dir = "corridor-sim";
  double volume = 400.0;
  std::uint64_t seed = 1;
  std::string routing = "dynamic";
  std::string signals = "corridor";
  std::string ev_from;
  std::string ev_to;
  double ev_depart_s = 200.0;
  double demand_end_s = 900.0;
  std::optional<double> end_s;
  double demand_scale = 1.0;
  std::string background_routes;
  std::string run_name;
  std::string result_file;
  bool no_ev = false;
  double congestion_period_s = 10.0;
  std::uint32_t incidents = 2;
  bool libsumo = false;
  std::string server;
  double gps_noise_m = 0.0;
  double gps_rate_hz = 1.0;
  std::vector<std::string> gps_outages;
  std::string token;
  std::uint32_t evs = 1;
  double inject_vph = 0.0;
  bool route_only = false;
  bool time_space = false;
  std::string ev_vclass = "emergency";
  bool rebuild_net = false;
  bool ntcip = false;
  std::string ntcip_listen = "127.0.0.1:16100";
  std::string read_community = "public";
  std::string write_community = "private";
};

sim::EvRouting parse_routing(const std::string& s) {
  if (const auto routing = sim::parse_ev_routing(s)) return *routing;
  throw UsageError("--routing must be static or dynamic, got '" + s + "'");
}

sim::EvSignals parse_signals(const std::string& s) {
  if (const auto signals = sim::parse_ev_signals(s)) return *signals;
  throw UsageError("--signals must be none, bluelight, corridor or corridor+bluelight, got '" + s + "'");
}

void run_sim(const SimOptions& o) {
  if (!(o.volume > 0.0 && o.volume <= 20000.0)) throw UsageError("--volume must be in (0, 20000] vehicles/hour");
  if (!(o.demand_scale > 0.0 && o.demand_scale <= 20.0)) throw UsageError("--demand-scale must be in (0, 20]");
  if (!(o.congestion_period_s >= 1.0)) throw UsageError("--congestion-period-s must be at least 1");
  if (!(o.ev_depart_s >= 0.0)) throw UsageError("--ev-depart-s must be >= 0");
  if (o.end_s && !(*o.end_s > o.ev_depart_s)) throw UsageError("--end-s must come after --ev-depart-s");
  const auto routing = parse_routing(o.routing);
  const auto signals = parse_signals(o.signals);
  if (!maps::sumo_class_bit(o.ev_vclass)) {
    throw UsageError("--ev-vclass must be a SUMO vehicle class (emergency, passenger, bus, ...), got '" + o.ev_vclass + "'");
  }
  const auto net = sim::build_scenario_net(o.scenario, o.work_dir, {o.rebuild_net});
  if (net.config && !o.background_routes.empty()) {
    throw UsageError("--background-routes is for generated scenarios; a .sumocfg brings its own demand (use --demand-scale)");
  }
  if (!net.config && o.demand_scale != 1.0) {
    throw UsageError("--demand-scale scales a .sumocfg scenario's own demand; a generated scenario takes --volume");
  }
  const auto scenario = sim::load_sumo_scenario(net, o.ev_vclass);
  // Times are after the scenario's begin: 0 for generated scenarios, the configuration's begin else.
  const double begin_s = net.config ? net.config->begin_s : 0.0;
  const double end_after_begin =
      o.end_s ? *o.end_s : (net.config && net.config->end_s ? *net.config->end_s - begin_s : 1800.0);
  if (!(end_after_begin > o.ev_depart_s)) {
    throw UsageError(fmt::format("the scenario ends {:g} s after its begin, before the EV departs (--ev-depart-s {:g})",
                                 end_after_begin, o.ev_depart_s));
  }
  sim::ClosedLoopConfig c;
  c.with_ev = !o.no_ev;
  c.routing = routing;
  c.signals = signals;
  std::tie(c.ev_from, c.ev_to) = sim::pick_ev_trip(*scenario, o.seed);
  if (!o.ev_from.empty()) c.ev_from = o.ev_from;
  if (!o.ev_to.empty()) c.ev_to = o.ev_to;
  c.ev_depart_s = begin_s + o.ev_depart_s;
  c.end_s = begin_s + end_after_begin;
  if (o.evs == 0 || o.evs > 16) throw UsageError("--evs must be in [1, 16]");
  if (o.evs > 1 && !o.server.empty()) throw UsageError("--evs above 1 runs in the in-process loop, not through --server");
  if (o.evs > 1 && o.no_ev) throw UsageError("--evs and --no-ev exclude each other");
  if (o.evs > 1) {
    c.more_evs = sim::conflicting_ev_trips(*scenario, {c.ev_from, c.ev_to, c.ev_depart_s, 1}, o.evs - 1, o.seed, c.ev_vmax_kmh);
    c.first_priority = static_cast<int>(o.evs);
  }
  c.vicinity = !o.route_only;
  if (!(o.inject_vph >= 0.0 && o.inject_vph <= 5000.0)) throw UsageError("--inject-vph must be in [0, 5000] vehicles/hour");
  c.inject_on_route_vph = o.inject_vph;
  c.record_time_space = o.time_space;
  c.demand_scale = o.demand_scale;
  c.seed = o.seed;
  c.congestion_period_s = o.congestion_period_s;
  c.incidents = o.incidents;
  c.backend = o.libsumo ? sim::SumoBackend::libsumo : sim::SumoBackend::traci;
  c.server_url = o.server;
  if ((o.gps_noise_m != 0.0 || !o.gps_outages.empty()) && o.server.empty()) {
    throw UsageError("--gps-noise-m and --gps-outage feed the server's map matcher: give --server");
  }
  if (!(o.gps_noise_m >= 0.0) || !(o.gps_rate_hz > 0.0 && o.gps_rate_hz <= 10.0)) {
    throw UsageError("--gps-noise-m must be >= 0 and --gps-rate-hz in (0, 10]");
  }
  if (!o.gps_outages.empty() && !(o.gps_noise_m > 0.0)) throw UsageError("--gps-outage needs --gps-noise-m > 0");
  c.gps_noise_m = o.gps_noise_m;
  c.gps_rate_hz = o.gps_rate_hz;
  for (const std::string& spec : o.gps_outages) {
    const auto colon = spec.find(':');
    double start = -1, duration = -1;
    try {
      if (colon != std::string::npos) start = std::stod(spec.substr(0, colon)), duration = std::stod(spec.substr(colon + 1));
    } catch (const std::exception&) {
    }
    if (!(start >= 0.0) || !(duration > 0.0)) throw UsageError("--gps-outage expects START:DURATION in seconds after the EV departs, got '" + spec + "'");
    c.gps_outages.emplace_back(start, start + duration);
  }
  c.server_token = o.token;
  if (o.ntcip) {
    if (o.server.empty()) throw UsageError("--ntcip puts the lights behind NTCIP agents that a server drives: give --server");
    const ListenAddress at = parse_listen_address(o.ntcip_listen, "--ntcip-listen", 1);
    c.ntcip = true;
    c.ntcip_host = at.host;
    c.ntcip_port = static_cast<unsigned short>(at.port);
    c.read_community = o.read_community;
    c.write_community = o.write_community;
  }
  if (!o.server.empty() && o.token.empty()) {
    const char* env = std::getenv("CORRIDOR_TOKEN");
    if (env == nullptr || *env == '\0') throw UsageError("--server needs --token (or $CORRIDOR_TOKEN) with the dispatcher and vehicle roles");
    c.server_token = env;
  }
  if (!net.config) {
    if (!o.background_routes.empty()) {
      if (!std::filesystem::is_regular_file(o.background_routes)) {
        throw UsageError("--background-routes: '" + o.background_routes + "' does not exist");
      }
      c.background_routes = std::filesystem::absolute(o.background_routes);
    } else {
      c.background_routes = sim::build_background_demand(net, {o.volume, o.demand_end_s, o.seed});
    }
  }
  c.out_dir = net.dir / "runs";
  c.run_name = o.run_name;
  if (c.run_name.empty()) {
    c.run_name = c.with_ev ? std::string(sim::to_string(c.routing)) + "_" + sim::to_string(c.signals) : "baseline";
    std::replace(c.run_name.begin(), c.run_name.end(), '+', '_');
  }
  if (c.run_name.find_first_of("/\\") != std::string::npos || c.run_name.starts_with('.')) {
    throw UsageError("--run-name must be a plain file name, got '" + c.run_name + "'");
  }
  sim::RunRecord record;
  record.scenario = net.name;
  record.with_ev = c.with_ev;
  record.routing = c.routing;
  record.signals = c.signals;
  record.volume = o.inject_vph > 0.0 ? o.inject_vph : (net.config ? 0.0 : o.volume);
  record.inject_on_route = o.inject_vph > 0.0;
  record.demand_scale = c.demand_scale;
  record.seed = o.seed;
  record.ev_from = c.ev_from;
  record.ev_to = c.ev_to;
  record.ev_depart_s = c.ev_depart_s;
  record.vicinity = c.vicinity;  // through a server, its own setting (serve --route-only)
  record.evs = o.evs;
  if (!net.rebuilt_from.empty()) {
    std::cerr << "corridor sim: " << net.rebuilt_from.string() << " was written by a newer netconvert; this run uses its "
              << "conversion by the installed one, " << net.net.string() << "\n";
  }
  try {
    record.result = sim::run_closed_loop(*scenario, c);
  } catch (const std::exception& e) {
    // A failed run is a record too, so that a collected matrix shows it as a row with its reason.
    if (!o.result_file.empty()) sim::write_record(o.result_file, sim::failed_run(record, e.what()));
    throw;
  }
  if (!o.result_file.empty()) sim::write_record(o.result_file, record);
  std::cout << sim::to_json_record(record).dump(2) << '\n';
}

}  // namespace

void register_sim_command(CLI::App& app) {
  auto o = std::make_shared<SimOptions>();
  auto* cmd = app.add_subcommand("sim", "One closed-loop SUMO run with an emergency vehicle; prints JSON");
  cmd->add_option("--scenario", o->scenario, "grid, nema-grid, a SUMO configuration (.sumocfg), a SUMO .net.xml, or an OSM file")
      ->capture_default_str();
  cmd->add_option("--work-dir", o->work_dir, "scenario files and run outputs")->capture_default_str();
  cmd->add_option("--volume", o->volume, "background vehicles per hour")->capture_default_str();
  cmd->add_option("--seed", o->seed, "random seed (demand, EV trip, incidents, SUMO)")->capture_default_str();
  cmd->add_option("--routing", o->routing, "static or dynamic")->capture_default_str();
  cmd->add_option("--signals", o->signals, "none, bluelight, corridor or corridor+bluelight")->capture_default_str();
  cmd->add_option("--ev-from", o->ev_from, "SUMO edge where the EV starts (default: picked from the seed)");
  cmd->add_option("--ev-to", o->ev_to, "SUMO edge where the EV ends");
  cmd->add_option("--ev-depart-s", o->ev_depart_s, "when the EV departs, in s after the scenario's begin")->capture_default_str();
  cmd->add_option("--demand-end-s", o->demand_end_s, "background traffic is inserted until then")->capture_default_str();
  cmd->add_option("--end-s", o->end_s,
                  "the run ends at the latest this many s after the scenario's begin (default: a .sumocfg's end, else 1800)");
  cmd->add_option("--demand-scale", o->demand_scale, "a .sumocfg's own demand times this (SUMO's --scale)")->capture_default_str();
  cmd->add_option("--background-routes", o->background_routes,
                  "a generated scenario's background routes (.rou.xml), instead of building them from --volume");
  cmd->add_flag("--no-ev", o->no_ev, "run without the EV: the baseline for other vehicles' delay");
  cmd->add_option("--run-name", o->run_name, "name of this run's files in the work directory (default ROUTING_SIGNALS)");
  cmd->add_option("--result", o->result_file, "also write the run's record (JSON) to this file, for experiment sumo --collect");
  cmd->add_option("--congestion-period-s", o->congestion_period_s, "how often measured travel times reach the planner")
      ->capture_default_str();
  cmd->add_option("--incidents", o->incidents, "speed drops on the EV's route after it left")->capture_default_str();
  cmd->add_flag("--libsumo", o->libsumo, "run SUMO in this process (libsumo) instead of over TraCI (libtraci)");
  cmd->add_option("--server", o->server,
                  "run the loop through this corridor serve (http://host:port), started with --map on the same .net.xml");
  cmd->add_option("--token", o->token, "bearer token for --server (default $CORRIDOR_TOKEN)");
  cmd->add_option("--gps-noise-m", o->gps_noise_m, "with --server: post noisy GPS fixes (σ in m) instead of SUMO's true positions")
      ->capture_default_str();
  cmd->add_option("--gps-rate-hz", o->gps_rate_hz, "with --gps-noise-m: fixes per second")->capture_default_str();
  cmd->add_option("--gps-outage", o->gps_outages,
                  "with --gps-noise-m: START:DURATION s after the EV departs with HDOP > 10 fixes; onboard odometry posts source vo");
  cmd->add_option("--evs", o->evs,
                  "EVs in the run: the further ones cross the first's lights from other approaches at the same time, "
                  "with falling priority")
      ->capture_default_str();
  cmd->add_flag("--route-only", o->route_only, "the seed's route-only preemption, without the vicinity rules");
  cmd->add_option("--inject-vph", o->inject_vph,
                  "the seed's Fig. 11: a flow of this many vehicles/hour along the EV's static route")
      ->capture_default_str();
  cmd->add_option("--ev-vclass", o->ev_vclass,
                  "the EV's SUMO vehicle class: its routes use only lanes and connections SUMO allows it")
      ->capture_default_str();
  cmd->add_flag("--rebuild-net", o->rebuild_net,
                "a net written by a newer netconvert is converted with the installed one into the work directory");
  cmd->add_flag("--ntcip", o->ntcip,
                "with --server: SUMO's lights behind virtual NTCIP 1202 controllers that the server drives over SNMP "
                "(serve --controllers with signal-agent --manifest-only's manifest for this net and --ntcip-listen)");
  cmd->add_option("--ntcip-listen", o->ntcip_listen, "with --ntcip: HOST:PORT of the first controller, the others on the next ports")
      ->capture_default_str();
  cmd->add_option("--read-community", o->read_community, "with --ntcip: the agents' read community")->capture_default_str();
  cmd->add_option("--write-community", o->write_community, "with --ntcip: the agents' write community")->capture_default_str();
  cmd->add_flag("--time-space", o->time_space,
                "write the EVs' trajectories and lights (RUN.ev_trajectory.csv, RUN.ev_signals.csv, RUN.time_space.svg)");
  cmd->callback([o] { run_sim(*o); });
}

namespace {

// The path of this executable, for emitted command lines that run it again.
std::filesystem::path self_binary() {
  std::error_code ec;
  const auto exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::filesystem::path("corridor") : exe;
}

}  // namespace

void register_sumo_experiment(CLI::App& experiment) {
  auto o = std::make_shared<sim::SumoExperimentOptions>();
  auto signals = std::make_shared<std::vector<std::string>>(
      std::vector<std::string>{"none", "bluelight", "corridor", "corridor+bluelight"});
  auto routings = std::make_shared<std::vector<std::string>>(std::vector<std::string>{"static", "dynamic"});
  auto emit_jobs = std::make_shared<std::string>();
  auto collect = std::make_shared<std::vector<std::string>>();
  auto end_s = std::make_shared<std::optional<double>>();
  auto* cmd = experiment.add_subcommand(
      "sumo", "Closed-loop SUMO matrix: routing x signal strategies over demand levels and seeds; run here, or emit and collect");
  cmd->add_option("--scenario", o->scenario, "grid, nema-grid, a SUMO configuration (.sumocfg), a .net.xml, or an OSM file")
      ->capture_default_str();
  cmd->add_option("--volumes", o->volumes, "generated scenarios: background volumes, vehicles/hour, comma-separated")
      ->delimiter(',')
      ->capture_default_str();
  cmd->add_option("--demand-scale", o->demand_scales, "a .sumocfg's own demand times these (SUMO's --scale), comma-separated")
      ->delimiter(',')
      ->capture_default_str();
  cmd->add_option("--signals", *signals, "signal strategies, comma-separated")->delimiter(',')->capture_default_str();
  cmd->add_option("--routings", *routings, "EV routing, comma-separated")->delimiter(',')->capture_default_str();
  cmd->add_option("--seeds", o->seeds, "seeds per demand level")->capture_default_str();
  cmd->add_option("--first-seed", o->first_seed, "seeds are first-seed, first-seed+1, ...")->capture_default_str();
  cmd->add_option("--out", o->out_dir, "output directory (runs, tables and plots)")->required();
  cmd->add_option("--demand-end-s", o->demand_end_s, "generated background traffic is inserted until then")->capture_default_str();
  cmd->add_option("--ev-depart-s", o->ev_depart_s, "when the EV departs, in s after the scenario's begin")->capture_default_str();
  cmd->add_option("--end-s", *end_s, "runs end at the latest this many s after the begin (default: a .sumocfg's end, else 2400)");
  cmd->add_option("--congestion-period-s", o->congestion_period_s, "how often measured travel times reach the planner")
      ->capture_default_str();
  cmd->add_option("--incidents", o->incidents, "speed drops on the EV's route after it left")->capture_default_str();
  cmd->add_option("--parallel", o->parallel, "SUMO runs at a time")->capture_default_str();
  cmd->add_option("--emit-jobs", *emit_jobs,
                  "write one `corridor sim` command line per run to this file instead of running them (for GNU parallel, "
                  "SSH hosts or a Slurm array), then --collect");
  cmd->add_option("--collect", *collect, "merge the run records (*.run.json) under these directories into --out")
      ->expected(1, -1);
  auto libsumo = std::make_shared<bool>(false);
  cmd->add_flag("--libsumo", *libsumo, "run SUMO inside each run's process (libsumo) instead of over TraCI");
  cmd->add_option("--evs", o->evs, "EVs per run (the further ones conflict with the first at its lights)")->capture_default_str();
  auto route_only = std::make_shared<bool>(false);
  cmd->add_flag("--route-only", *route_only, "the seed's route-only preemption, without the vicinity rules");
  cmd->add_flag("--inject-on-route", o->inject_on_route,
                "the seed's Fig. 11: --volumes are injected along each EV's static route, over --background-vph");
  cmd->add_option("--background-vph", o->background_vph, "with --inject-on-route: background vehicles/hour")->capture_default_str();
  cmd->add_option("--ev-vclass", o->ev_vclass, "the EV's SUMO vehicle class")->capture_default_str();
  cmd->add_flag("--rebuild-net", o->rebuild_net,
                "a net written by a newer netconvert is converted with the installed one into the output directory");
  auto keep_going = std::make_shared<bool>(false);
  cmd->add_flag("--keep-going", *keep_going, "exit 0 even when runs failed (they are rows with status failed either way)");
  // Every run is a row; a failed one makes the command fail unless --keep-going.
  const auto report = [o, keep_going](const sim::ExperimentTables& tables) {
    std::ifstream md(o->out_dir / "sumo_summary.md");
    std::cout << md.rdbuf() << "\nOutput in " << o->out_dir.string() << "\n";
    if (!tables.failures.empty() && !*keep_going) {
      throw std::runtime_error(std::to_string(tables.failures.size()) + " run(s) did not complete; they are listed in " +
                       (o->out_dir / "sumo_summary.md").string() + " (give --keep-going to exit 0 all the same)");
    }
  };
  cmd->callback([o, signals, routings, emit_jobs, collect, end_s, libsumo, route_only, report] {
    if (!emit_jobs->empty() && !collect->empty()) throw UsageError("--emit-jobs and --collect are two steps: give one");
    if (!collect->empty()) {
      std::vector<std::filesystem::path> dirs(collect->begin(), collect->end());
      report(sim::collect_sumo_experiment(dirs, o->out_dir));
      return;
    }
    if (!maps::sumo_class_bit(o->ev_vclass)) {
      throw UsageError("--ev-vclass must be a SUMO vehicle class (emergency, passenger, bus, ...), got '" + o->ev_vclass + "'");
    }
    o->backend = *libsumo ? sim::SumoBackend::libsumo : sim::SumoBackend::traci;
    o->vicinity = !*route_only;
    if (o->evs == 0 || o->evs > 16) throw UsageError("--evs must be in [1, 16]");
    o->end_s = *end_s;
    o->signals.clear();
    for (const std::string& s : *signals) o->signals.push_back(parse_signals(s));
    o->routings.clear();
    for (const std::string& r : *routings) o->routings.push_back(parse_routing(r));
    if (o->seeds == 0 || o->seeds > 1000) throw UsageError("--seeds must be in [1, 1000]");
    if (o->parallel == 0 || o->parallel > 64) throw UsageError("--parallel must be in [1, 64]");
    if (o->end_s && !(*o->end_s > o->ev_depart_s)) throw UsageError("--end-s must come after --ev-depart-s");
    if (!emit_jobs->empty()) {
      const std::size_t n = sim::emit_sumo_jobs(*o, *emit_jobs, self_binary());
      std::cout << n << " runs written to " << *emit_jobs << ". Run them, for example with\n  parallel -j2 < " << *emit_jobs
                << "\nthen merge the results:\n  corridor experiment sumo --collect " << (o->out_dir / "runs").string()
                << " --out " << o->out_dir.string() << "\n";
      return;
    }
    report(sim::run_sumo_experiment(*o));
  });
}

}  // namespace corridor::app
