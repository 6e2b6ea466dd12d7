#include "app/signal_agent_command.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <csignal>
#include <fstream>
#include <iostream>
#include <memory>

#include "app/cli_error.hpp"
#include "app/listen_address.hpp"
#include "app/map_options.hpp"
#include "maps/map_loader.hpp"
#include "ntcip/virtual_agents.hpp"
#include "preemption/simulated_signal_controller.hpp"

namespace corridor::app {
namespace {

struct AgentOptions {
  MapOptions map;
  std::string listen = "127.0.0.1:16100";
  std::string read_community = "public";
  std::string write_community = "private";
  std::string manifest;
  bool manifest_only = false;
  std::string v3_user;
  std::string v3_auth_password;
  std::string v3_priv_password;
  std::string state_dir;
  double call_timeout_s = 30.0;
  double max_presence_s = 180.0;
};

volatile std::sig_atomic_t g_stop = 0;

double wall_s() { return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count(); }

void write_manifest(const std::string& file, const std::vector<ntcip::ControllerConfig>& manifest) {
  const std::string tmp = file + ".tmp";
  {
    std::ofstream out(tmp, std::ios::trunc);
    out << ntcip::to_json(manifest).dump(2) << '\n';
    if (!out) throw std::runtime_error("cannot write the manifest " + tmp);
  }
  std::filesystem::rename(tmp, file);
}

void run_agent(const AgentOptions& o) {
  const ListenAddress at = parse_listen_address(o.listen, "--listen", 1);
  if (o.read_community.empty() || o.write_community.empty()) throw UsageError("--read-community and --write-community must not be empty");
  if (o.read_community == o.write_community) throw UsageError("--read-community and --write-community must differ: the read one may not SET");
  if (!(o.call_timeout_s >= 1.0 && o.call_timeout_s <= 3600.0)) throw UsageError("--call-timeout-s must be in [1, 3600]");
  if (!(o.max_presence_s >= 10.0 && o.max_presence_s <= 3600.0)) throw UsageError("--max-presence-s must be in [10, 3600]");
  ntcip::VirtualAgentsConfig config;
  config.host = at.host;
  config.first_port = static_cast<unsigned short>(at.port);
  config.security.read_community = o.read_community;
  config.security.write_community = o.write_community;
  if (!o.v3_user.empty()) {
    if (o.v3_auth_password.size() < 8 || o.v3_priv_password.size() < 8) {
      throw UsageError("--v3-auth-password and --v3-priv-password must be at least 8 characters (RFC 3414)");
    }
    config.security.v3_user = ntcip::UsmUser{o.v3_user, o.v3_auth_password, o.v3_priv_password};
  }
  config.security.state_dir = o.state_dir.empty() ? std::filesystem::temp_directory_path() / ("corridor-signal-agent-" + std::to_string(at.port))
                                                  : std::filesystem::path(o.state_dir);
  config.security.engine_name = "corridor-" + std::to_string(at.port);
  config.timing.call_timeout_s = o.call_timeout_s;
  config.timing.max_presence_s = o.max_presence_s;

  const maps::RoadGraph graph = load_map_from_options(o.map);
  const std::filesystem::path map_file = o.map.map_file.empty() ? CORRIDOR_DEFAULT_MAP : o.map.map_file;
  const maps::SignalMap signals = maps::signal_plans_for(map_file, graph);
  if (signals.signals.empty()) throw UsageError("the map has no signalized intersection to serve");
  if (o.manifest_only) {
    if (o.manifest.empty()) throw UsageError("--manifest-only needs --manifest FILE");
    std::vector<ntcip::ControllerConfig> manifest;
    try {
      manifest = ntcip::virtual_manifest(graph, signals, config);
    } catch (const std::invalid_argument& e) {
      throw UsageError(e.what());
    }
    write_manifest(o.manifest, manifest);
    std::cout << manifest.size() << " controllers on " << at.host << ":" << at.port << ".." << at.port + manifest.size() - 1
              << ", manifest " << o.manifest << std::endl;
    return;
  }
  const double start = wall_s();
  preemption::SimulatedSignalController controller(signals.signals, start);
  ntcip::VirtualAgents agents(graph, signals, controller, config, start);
  if (!o.manifest.empty()) write_manifest(o.manifest, agents.manifest());
  std::cout << agents.manifest().size() << " NTCIP 1202 controllers listening on UDP " << at.host << ":" << at.port << ".."
            << at.port + agents.manifest().size() - 1 << (o.manifest.empty() ? "" : ", manifest " + o.manifest) << std::endl;
  std::signal(SIGINT, [](int) { g_stop = 1; });
  std::signal(SIGTERM, [](int) { g_stop = 1; });
  while (g_stop == 0) {
    const double now = wall_s();
    controller.advance(now);
    agents.poll(50, now);
  }
  spdlog::info("event=signal_agent_stopped requests={}", agents.requests_answered());
}

}  // namespace

void register_signal_agent_command(CLI::App& app) {
  auto o = std::make_shared<AgentOptions>();
  auto* cmd = app.add_subcommand("signal-agent",
                                 "Virtual NTCIP 1202 signal controllers: one SNMP agent per signalized intersection of the map, on "
                                 "consecutive UDP ports, running its normal program and real preempt sequences");
  add_map_options(*cmd, o->map);
  cmd->add_option("--listen", o->listen, "HOST:PORT of the first intersection; the others follow on PORT+1, PORT+2, ...")
      ->capture_default_str();
  cmd->add_option("--read-community", o->read_community, "SNMPv1/v2c community for GET, GETNEXT and GETBULK")->capture_default_str();
  cmd->add_option("--write-community", o->write_community, "SNMPv1/v2c community that may also SET")->capture_default_str();
  cmd->add_option("--manifest", o->manifest,
                  "write the agents' manifest here (JSON, one object per agent: a valid --controllers file for corridor serve)");
  cmd->add_flag("--manifest-only", o->manifest_only, "write the manifest and exit, without serving");
  cmd->add_option("--v3-user", o->v3_user, "also accept SNMPv3 (USM, SHA/AES authPriv) for this user");
  cmd->add_option("--v3-auth-password", o->v3_auth_password, "the v3 user's authentication password (8 characters or more)");
  cmd->add_option("--v3-priv-password", o->v3_priv_password, "the v3 user's privacy password (8 characters or more)");
  cmd->add_option("--state-dir", o->state_dir, "where the SNMP engine keeps its boot counter (default: a directory per port under /tmp)");
  cmd->add_option("--call-timeout-s", o->call_timeout_s, "a preempt call not re-asserted for this long is dropped")->capture_default_str();
  cmd->add_option("--max-presence-s", o->max_presence_s, "no preempt dwells longer (the call must be removed and placed again)")
      ->capture_default_str();
  cmd->callback([o] { run_agent(*o); });
}

}  // namespace corridor::app
