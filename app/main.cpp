// The `corridor` executable: parses the command line and hands over to the modules.
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <iostream>

#include "app/bench_command.hpp"
#include "app/cli_error.hpp"
#include "app/experiment_command.hpp"
#include "app/localize_command.hpp"
#include "app/map_command.hpp"
#include "app/match_command.hpp"
#include "app/preemption_command.hpp"
#include "app/route_command.hpp"
#include "app/serve_command.hpp"
#include "app/signal_agent_command.hpp"
#include "app/sim_command.hpp"
#include "app/vo_command.hpp"
#include "maps/errors.hpp"
#include "server/store.hpp"

int main(int argc, char** argv) {
  // Logs go to stderr so that stdout carries only the command's JSON.
  spdlog::set_default_logger(spdlog::stderr_color_mt("corridor"));
  spdlog::set_pattern("%Y-%m-%dT%H:%M:%S.%e %^%l%$ %v");

  CLI::App app{"Corridor: green corridors for emergency vehicles"};
  app.require_subcommand(1);
  std::string log_level = "warn";
  app.add_option("--log-level", log_level, "trace, debug, info, warn, error or off")->capture_default_str();
  app.parse_complete_callback([&] { spdlog::set_level(spdlog::level::from_str(log_level)); });
  corridor::app::register_route_command(app);
  corridor::app::register_map_command(app);
  corridor::app::register_bench_command(app);
  corridor::app::register_preemption_command(app);
  corridor::app::register_serve_command(app);
  corridor::app::register_experiment_command(app);
  corridor::app::register_sim_command(app);
  corridor::app::register_signal_agent_command(app);
  corridor::app::register_vo_command(app);
  corridor::app::register_match_command(app);
  corridor::app::register_localize_command(app);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // CLI11 prints the message; every usage error exits with 2, like UsageError below.
    const int rc = app.exit(e);
    return rc == 0 ? 0 : 2;
  } catch (const corridor::app::UsageError& e) {
    std::cerr << "error: " << e.what() << '\n';
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << '\n';
    return 1;
  }
  return 0;
}
