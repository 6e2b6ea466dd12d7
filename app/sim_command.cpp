#include "app/sim_command.hpp"

#include <nlohmann/json.hpp>

#include <cstdlib>
#include <fstream>
#include <iostream>
#include <memory>

#include "app/cli_error.hpp"
#include "sim/closed_loop.hpp"
#include "sim/result_json.hpp"
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
  double end_s = 1800.0;
  double congestion_period_s = 10.0;
  std::uint32_t incidents = 2;
  bool libsumo = false;
  std::string server;
  double gps_noise_m = 0.0;
  double gps_rate_hz = 1.0;
  std::vector<std::string> gps_outages;
  std::string token;
};

sim::EvRouting parse_routing(const std::string& s) {
  if (s == "static") return sim::EvRouting::static_route;
  if (s == "dynamic") return sim::EvRouting::dynamic_route;
  throw UsageError("--routing must be static or dynamic, got '" + s + "'");
}

sim::EvSignals parse_signals(const std::string& s) {
  if (s == "none") return sim::EvSignals::none;
  if (s == "bluelight") return sim::EvSignals::bluelight;
  if (s == "corridor") return sim::EvSignals::corridor;
  throw UsageError("--signals must be none, bluelight or corridor, got '" + s + "'");
}

void run_sim(const SimOptions& o) {
  if (!(o.volume > 0.0 && o.volume <= 20000.0)) throw UsageError("--volume must be in (0, 20000] vehicles/hour");
  if (!(o.congestion_period_s >= 1.0)) throw UsageError("--congestion-period-s must be at least 1");
  if (!(o.end_s > o.ev_depart_s && o.ev_depart_s >= 0.0)) throw UsageError("--end-s must come after --ev-depart-s");
  const auto net = sim::build_scenario_net(o.scenario, o.work_dir);
  const auto scenario = sim::load_sumo_scenario(net.name, net.dir, net.net);
  sim::ClosedLoopConfig c;
  c.routing = parse_routing(o.routing);
  c.signals = parse_signals(o.signals);
  std::tie(c.ev_from, c.ev_to) = sim::pick_ev_trip(*scenario, o.seed);
  if (!o.ev_from.empty()) c.ev_from = o.ev_from;
  if (!o.ev_to.empty()) c.ev_to = o.ev_to;
  c.ev_depart_s = o.ev_depart_s;
  c.end_s = o.end_s;
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
  if (!o.server.empty() && o.token.empty()) {
    const char* env = std::getenv("CORRIDOR_TOKEN");
    if (env == nullptr || *env == '\0') throw UsageError("--server needs --token (or $CORRIDOR_TOKEN) with the dispatcher and vehicle roles");
    c.server_token = env;
  }
  c.background_routes = sim::build_background_demand(net, {o.volume, o.demand_end_s, o.seed});
  c.out_dir = net.dir / "runs";
  c.run_name = std::string(sim::to_string(c.routing)) + "_" + sim::to_string(c.signals);
  const auto r = sim::run_closed_loop(*scenario, c);
  nlohmann::json out = r;
  out["scenario"] = net.name;
  out["ev_from"] = c.ev_from;
  out["ev_to"] = c.ev_to;
  out["routing"] = o.routing;
  out["signals"] = o.signals;
  out["volume"] = o.volume;
  out["seed"] = o.seed;
  std::cout << out.dump(2) << '\n';
}

}  // namespace

void register_sim_command(CLI::App& app) {
  auto o = std::make_shared<SimOptions>();
  auto* cmd = app.add_subcommand("sim", "One closed-loop SUMO run with an emergency vehicle; prints JSON");
  cmd->add_option("--scenario", o->scenario, "grid, a SUMO .net.xml, or an OSM file")->capture_default_str();
  cmd->add_option("--work-dir", o->work_dir, "scenario files and run outputs")->capture_default_str();
  cmd->add_option("--volume", o->volume, "background vehicles per hour")->capture_default_str();
  cmd->add_option("--seed", o->seed, "random seed (demand, EV trip, incidents, SUMO)")->capture_default_str();
  cmd->add_option("--routing", o->routing, "static or dynamic")->capture_default_str();
  cmd->add_option("--signals", o->signals, "none, bluelight or corridor")->capture_default_str();
  cmd->add_option("--ev-from", o->ev_from, "SUMO edge where the EV starts (default: picked from the seed)");
  cmd->add_option("--ev-to", o->ev_to, "SUMO edge where the EV ends");
  cmd->add_option("--ev-depart-s", o->ev_depart_s, "when the EV departs")->capture_default_str();
  cmd->add_option("--demand-end-s", o->demand_end_s, "background traffic is inserted until then")->capture_default_str();
  cmd->add_option("--end-s", o->end_s, "the run ends at the latest then")->capture_default_str();
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
  cmd->callback([o] { run_sim(*o); });
}

void register_sumo_experiment(CLI::App& experiment) {
  auto o = std::make_shared<sim::SumoExperimentOptions>();
  auto volumes = std::make_shared<std::string>("200,400,600,800");
  auto* cmd = experiment.add_subcommand(
      "sumo", "Closed-loop SUMO matrix: static/dynamic routing x none/bluelight/corridor signals over volumes and seeds");
  cmd->add_option("--scenario", o->scenario, "grid, a SUMO .net.xml, or an OSM file (.osm, .osm.gz, .osm.pbf)")
      ->capture_default_str();
  cmd->add_option("--volumes", *volumes, "background volumes, vehicles/hour, comma-separated")->capture_default_str();
  cmd->add_option("--seeds", o->seeds, "seeds per volume")->capture_default_str();
  cmd->add_option("--first-seed", o->first_seed, "seeds are first-seed, first-seed+1, ...")->capture_default_str();
  cmd->add_option("--out", o->out_dir, "output directory")->required();
  cmd->add_option("--demand-end-s", o->demand_end_s, "background traffic is inserted until then")->capture_default_str();
  cmd->add_option("--ev-depart-s", o->ev_depart_s, "when the EV departs")->capture_default_str();
  cmd->add_option("--end-s", o->end_s, "every run ends at the latest then")->capture_default_str();
  cmd->add_option("--congestion-period-s", o->congestion_period_s, "how often measured travel times reach the planner")
      ->capture_default_str();
  cmd->add_option("--incidents", o->incidents, "speed drops on the EV's route after it left")->capture_default_str();
  cmd->add_option("--parallel", o->parallel, "SUMO runs at a time")->capture_default_str();
  auto libsumo = std::make_shared<bool>(false);
  cmd->add_flag("--libsumo", *libsumo, "run SUMO inside each run's process (libsumo) instead of over TraCI");
  cmd->callback([o, volumes, libsumo] {
    o->backend = *libsumo ? sim::SumoBackend::libsumo : sim::SumoBackend::traci;
    o->volumes.clear();
    std::string item;
    for (std::size_t i = 0; i <= volumes->size(); ++i) {
      if (i == volumes->size() || (*volumes)[i] == ',') {
        try {
          std::size_t used = 0;
          const double v = std::stod(item, &used);
          if (used != item.size()) throw std::invalid_argument(item);
          o->volumes.push_back(v);
        } catch (const std::exception&) {
          throw UsageError("--volumes expects numbers separated by commas, such as 200,400,600; got '" + *volumes + "'");
        }
        item.clear();
      } else {
        item += (*volumes)[i];
      }
    }
    if (o->seeds == 0 || o->seeds > 1000) throw UsageError("--seeds must be in [1, 1000]");
    if (o->parallel == 0 || o->parallel > 64) throw UsageError("--parallel must be in [1, 64]");
    if (!(o->end_s > o->ev_depart_s)) throw UsageError("--end-s must come after --ev-depart-s");
    sim::run_sumo_experiment(*o);
    std::ifstream md(o->out_dir / "sumo_summary.md");
    std::cout << md.rdbuf() << "\nOutput in " << o->out_dir.string() << "\n";
  });
}

}  // namespace corridor::app
