#include "app/serve_command.hpp"

#include <boost/asio/ip/address.hpp>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
#include <random>
#include <thread>

#include "app/cli_error.hpp"
#include "app/map_options.hpp"
#include "ntcip/controllers_file.hpp"
#include "server/demo_driver.hpp"
#include "server/dispatch_service.hpp"
#include "server/http_server.hpp"
#include "maps/synthetic_grid.hpp"
#include "server/router.hpp"
#include "web/embedded_files.hpp"

namespace corridor::app {
namespace {

struct ServeOptions {
  MapOptions map;
  std::string db = "corridor.db";
  std::string listen = "127.0.0.1:8080";
  std::string config;
  int threads = 2;
  int repair_threads = 0;  // 0: server::default_repair_threads(threads)
  int repair_priority = 0;
  int background_nice = 10;
  bool demo = false;
  bool route_only = false;
  std::string controllers;
  server::PlannerGraph planner_graph = server::PlannerGraph::automatic;
};

std::string random_token() {
  std::random_device rd;
  std::string t;
  for (int i = 0; i < 32; ++i) t += "0123456789abcdef"[rd() % 16];
  return t;
}

nlohmann::json read_config(const std::string& path) {
  if (path.empty()) return nlohmann::json::object();
  std::ifstream in(path);
  if (!in) throw UsageError("config file not found: '" + path + "'");
  auto j = nlohmann::json::parse(in, nullptr, false);
  if (j.is_discarded() || !j.is_object()) throw UsageError("config file '" + path + "' is not a JSON object");
  return j;
}

// One number of the config's "limits", within [lo, hi]; a usage error that names the field otherwise.
double limit_in(const nlohmann::json& limits, const char* key, double fallback, double lo, double hi) {
  const auto it = limits.find(key);
  if (it == limits.end()) return fallback;
  if (!it->is_number()) throw UsageError(fmt::format("config: limits.{} must be a number", key));
  const double v = it->get<double>();
  if (!(v >= lo && v <= hi)) throw UsageError(fmt::format("config: limits.{} must be within [{}, {}], got {}", key, lo, hi, v));
  return v;
}

void read_limits(const nlohmann::json& config, server::RouterConfig& router, server::ServerLimits& limits) {
  const auto it = config.find("limits");
  if (it == config.end()) return;
  if (!it->is_object()) throw UsageError("config: 'limits' must be an object");
  for (const auto& [key, value] : it->items()) {
    if (key != "rate_per_token_per_s" && key != "burst_per_token" && key != "body_limit_bytes" &&
        key != "header_limit_bytes" && key != "read_timeout_s") {
      throw UsageError("config: unknown limit '" + key +
                       "' (known: rate_per_token_per_s, burst_per_token, body_limit_bytes, header_limit_bytes, read_timeout_s)");
    }
  }
  router.rate_per_token_per_s = limit_in(*it, "rate_per_token_per_s", router.rate_per_token_per_s, 1e-3, 1e9);
  router.burst_per_token = limit_in(*it, "burst_per_token", router.burst_per_token, 1.0, 1e9);
  // Integers where the server counts bytes and seconds: a fraction is rounded down.
  limits.body_limit_bytes = static_cast<std::size_t>(
      limit_in(*it, "body_limit_bytes", static_cast<double>(limits.body_limit_bytes), 1024.0, 1024.0 * 1024 * 1024));
  limits.header_limit_bytes = static_cast<std::size_t>(
      limit_in(*it, "header_limit_bytes", static_cast<double>(limits.header_limit_bytes), 1024.0, 1024.0 * 1024));
  limits.read_timeout_s = static_cast<int>(limit_in(*it, "read_timeout_s", limits.read_timeout_s, 1.0, 3600.0));
}

void run_serve(const ServeOptions& o) {
  const auto colon = o.listen.rfind(':');
  if (colon == std::string::npos) throw UsageError("--listen expects HOST:PORT, got '" + o.listen + "'");
  const std::string host = o.listen.substr(0, colon);
  int port = -1;
  try {
    port = std::stoi(o.listen.substr(colon + 1));
  } catch (const std::exception&) {
  }
  if (port < 0 || port > 65535) throw UsageError("--listen port must be 0..65535, got '" + o.listen.substr(colon + 1) + "'");
  {
    boost::system::error_code ec;
    (void)boost::asio::ip::make_address(host, ec);
    if (ec) throw UsageError("--listen host must be an IP address (for example 127.0.0.1 or ::1), got '" + host + "'");
  }
  if (o.threads < 1 || o.threads > 64) throw UsageError("--threads must be 1..64");
  const nlohmann::json config = read_config(o.config);

  server::TokenAuth auth;
  std::string dev_token;
  try {
    auth.add_from_config(config);
    const char* env = std::getenv("CORRIDOR_DEV_TOKEN");
    const std::string dev = env != nullptr && *env != '\0' ? std::string(env) : random_token();
    auth.add(dev, {"development", server::kAllRoles, std::nullopt});
    dev_token = dev;
  } catch (const server::AuthConfigError& e) {
    throw UsageError(e.what());
  }
  server::RouterConfig router_config;
  server::ServerLimits limits;
  read_limits(config, router_config, limits);

  const maps::RoadGraph graph = load_map_from_options(o.map);
  server::Store store(o.db);
  const auto now = [] {
    return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
  };
  const std::filesystem::path map_file = o.map.map_file.empty() ? CORRIDOR_DEFAULT_MAP : o.map.map_file;
  server::DispatchConfig dispatch;
  dispatch.repair_threads = o.repair_threads > 0 ? o.repair_threads : server::default_repair_threads(o.threads);
  dispatch.repair_realtime_priority = o.repair_priority;
  dispatch.background_nice = o.background_nice;
  limits.io_nice = o.background_nice;
  dispatch.planner_graph = o.planner_graph;
  // Vicinity-aware preemption: the detectors' queues (POST /v1/signals/{id}/counts with queue_m)
  // start holds early enough to clear them; without detector reports it is route-only.
  dispatch.preemption.vicinity.enabled = !o.route_only;
  if (!o.controllers.empty()) {
    try {
      dispatch.field_controllers = ntcip::read_controllers_file(o.controllers);
    } catch (const ntcip::ControllersFileError& e) {
      throw UsageError(std::string("--controllers: ") + e.what());
    }
  }
  std::optional<server::DispatchService> service_slot;
  try {
    service_slot.emplace(graph, maps::signal_plans_for(map_file, graph), dispatch, &store, now());
  } catch (const ntcip::ControllersFileError& e) {
    throw UsageError(std::string("--controllers: ") + e.what());
  }
  server::DispatchService& service = *service_slot;
  if (!dispatch.field_controllers.empty()) {
    std::cout << dispatch.field_controllers.size() << " signal controllers driven over NTCIP 1202 (" << o.controllers << ")" << std::endl;
  }
  std::vector<server::StaticAsset> console;
  for (const auto& f : web::embedded_files()) {
    console.push_back({f.path, {reinterpret_cast<const char*>(f.data), f.size}});
  }
  server::Router router(service, std::move(auth), router_config, now, std::make_shared<server::StaticSite>(console));
  server::HttpServer http(router, service, limits, host, static_cast<unsigned short>(port), o.threads);
  // Printed only once the database and the port are ours, so a server that cannot start shows
  // its error and no token.
  std::cout << "development token (all roles): " << dev_token << std::endl;
  std::cout << "listening on http://" << host << ":" << http.port() << " (map: " << graph.node_count() << " nodes, "
            << service.active_mission_count() << " active missions resumed, db: " << o.db << ")" << std::endl;
  // Which graph missions plan on, and for `auto` why: a user sees it without raising the log level.
  if (const auto* h = service.hierarchy()) {
    std::cout << fmt::format("planning on a contraction hierarchy shared by all missions ({:.1f} arcs per vertex)",
                             h->density())
              << std::endl;
  } else {
    std::cout << "planning on the turn graph, each mission its own search" << std::endl;
  }
  std::cout << "console: open http://" << (host == "0.0.0.0" ? std::string("127.0.0.1") : host) << ":" << http.port()
            << "/ and paste the token above" << std::endl;
  spdlog::info("event=serving address={}:{} threads={}", host, http.port(), o.threads);
  // Declared after the server, so it stops (and is joined) before the server goes.
  std::jthread demo;
  if (o.demo) {
    std::cout << "demo: simulated vehicles drive missions on this map (vehicle ids demo-N)" << std::endl;
    demo = std::jthread([&service, now](std::stop_token stop) {
      server::DemoDriver driver(service, {});
      double last = now();
      while (!stop.stop_requested()) {
        std::this_thread::sleep_for(std::chrono::seconds(1));
        const double t = now();
        driver.step(t, t - last);
        last = t;
      }
    });
  }
  http.run();
  spdlog::info("event=stopped");
}

}  // namespace

void add_planner_graph_option(CLI::App& cmd, server::PlannerGraph& out) {
  const std::map<std::string, server::PlannerGraph> names{{"auto", server::PlannerGraph::automatic},
                                                          {"turn-graph", server::PlannerGraph::turn_graph},
                                                          {"hierarchy", server::PlannerGraph::hierarchy}};
  cmd.add_option("--planner-graph", out,
                 "what missions plan on: the turn graph, a contraction hierarchy shared by all missions, or auto (the "
                 "hierarchy unless it comes out dense, as on a city-wide grid)")
      ->transform(CLI::CheckedTransformer(names))
      ->default_str("auto");
}

void register_serve_command(CLI::App& app) {
  // The API description does not depend on the map: a tiny grid stands in for one.
  app.add_subcommand("openapi", "Print the API's OpenAPI 3 description (what GET /v1/openapi.json serves)")->callback([] {
    maps::GridSpec spec;
    spec.rows = 2;
    spec.cols = 2;
    const maps::RoadGraph graph = maps::make_perturbed_grid(spec);
    server::DispatchConfig config;
    config.planner_graph = server::PlannerGraph::turn_graph;  // nothing is planned here
    server::DispatchService service(graph, config, nullptr, 0.0);
    const server::Router router(service, {}, {}, [] { return 0.0; });
    std::cout << router.openapi().dump(2) << std::endl;
  });
  auto o = std::make_shared<ServeOptions>();
  auto* cmd = app.add_subcommand("serve", "Run the dispatch server (HTTP/JSON API and WebSocket stream)");
  add_map_options(*cmd, o->map);
  cmd->add_option("--db", o->db, "SQLite database (created if missing)")->capture_default_str();
  cmd->add_option("--listen", o->listen, "HOST:PORT to listen on (port 0 picks a free one)")->capture_default_str();
  cmd->add_option("--config", o->config, "JSON config: tokens with roles, limits");
  cmd->add_option("--threads", o->threads, "I/O threads")->capture_default_str();
  cmd->add_option("--repair-threads", o->repair_threads,
                  "threads repairing plans after a congestion change, its request's I/O thread included (0 = half of "
                  "--threads, at least 1: docs/routing.md)")
      ->check(CLI::Range(0, 64))
      ->capture_default_str();
  cmd->add_option("--repair-priority", o->repair_priority,
                  "0, or the real-time (SCHED_FIFO) priority repairs after a congestion change run at, so other "
                  "work cannot preempt them (needs root or CAP_SYS_NICE; docs/routing.md)")
      ->check(CLI::Range(0, 99))
      ->capture_default_str();
  cmd->add_option("--background-nice", o->background_nice,
                  "nice steps the I/O threads (position reports, the event stream) and the commit writer take below "
                  "the threads that plan and repair routes, so a contended core goes to repairs first (0 = all "
                  "equal; needs no privilege; docs/routing.md)")
      ->check(CLI::Range(0, 19))
      ->capture_default_str();
  add_planner_graph_option(*cmd, o->planner_graph);
  cmd->add_option("--controllers", o->controllers,
                  "JSON file of field signal controllers driven over NTCIP 1202 (SNMP): per intersection its address, SNMP "
                  "version and credentials, and preempt or phase-control wiring (docs/field.md); a signal-agent manifest is one");
  cmd->add_flag("--route-only", o->route_only,
                "preempt from the vehicle's predicted arrival alone, without the vicinity rules that read detectors' queues");
  cmd->add_flag("--demo", o->demo,
                 "drive simulated vehicles along their missions' routes, and now and then congest a route ahead");
  cmd->callback([o] { run_serve(*o); });
}

}  // namespace corridor::app
