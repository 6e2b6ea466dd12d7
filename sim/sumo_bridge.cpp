#include "sim/sumo_bridge.hpp"

#include <libsumo/libtraci.h>
#include <spdlog/spdlog.h>

#include <atomic>
#include <chrono>
#include <thread>
#include <fmt/format.h>

#include "sim/errors.hpp"

namespace corridor::sim {
namespace {

std::string join_paths(const std::vector<std::filesystem::path>& files) {
  std::string s;
  for (const auto& f : files) s += (s.empty() ? "" : ",") + f.string();
  return s;
}

std::atomic<int> bridge_counter{0};

}  // namespace

void write_launch_config(const SumoLaunch& launch, const SumoOptionCatalog& catalog) {
  std::vector<std::pair<std::string, std::string>> owned{
      {"net-file", launch.net.string()},
      {"additional-files", join_paths(launch.additional)},
      {"scale", fmt::format("{:g}", launch.scale)},
      {"log", launch.log.string()},
      {"step-length", fmt::format("{:g}", launch.step_length_s)},
      {"end", fmt::format("{:g}", launch.end_s)},
      {"seed", std::to_string(launch.seed)},
      {"random", "false"},
      {"output-prefix", ""},  // it would move the run's own outputs too
      {"no-step-log", "true"},
      {"duration-log.disable", "true"},
      {"collision.action", "warn"},
      // TraCI's port is the run's: the command line gives it, once (sumo_command).
      {"remote-port", "0"},
      {"num-clients", "1"},
  };
  if (!launch.routes.empty()) owned.emplace_back("route-files", join_paths(launch.routes));
  if (!launch.tripinfo.empty()) {
    owned.emplace_back("tripinfo-output", launch.tripinfo.string());
    owned.emplace_back("tripinfo-output.write-unfinished", "true");
  }
  // A user's scenario keeps its own teleport and route-error settings.
  if (launch.user_options.empty()) {
    owned.emplace_back("time-to-teleport", "300");
    owned.emplace_back("ignore-route-errors", "true");
  }
  const auto keep = [](const std::string&, const std::string& value) { return value; };
  write_run_config(launch.run_config, catalog, launch.user_options, launch.user_dir, owned,
                   launch.redirect_output ? launch.redirect_output : keep);
}

std::vector<std::string> sumo_command(const SumoLaunch& launch, std::optional<int> port) {
  std::vector<std::string> cmd{launch.sumo_binary, "-c", launch.run_config.string()};
  if (port) cmd.insert(cmd.end(), {"--remote-port", std::to_string(*port), "--num-clients", "1"});
  return cmd;
}

SumoBridge::SumoBridge(const SumoLaunch& launch) : log_(launch.log) {
  // A port found free can be taken by someone else before SUMO binds it; then SUMO exits, and a
  // fresh port is tried.
  for (int attempt = 1;; ++attempt) {
    const int port = free_tcp_port();
    const std::vector<std::string> cmd = sumo_command(launch, port);
    process_ = std::make_unique<ChildProcess>(cmd, log_);
    if (!wait_until_listening(port, *process_, 60.0)) {
      process_->kill();
      process_->wait();
      process_.reset();
      if (attempt < 3) continue;
      throw SimError("SUMO did not start listening on port " + std::to_string(port) + "; end of " + log_.string() + ":" +
                     tail_of(log_));
    }
    label_ = fmt::format("corridor{}", bridge_counter++);
    try {
      // SUMO already listens: one attempt, so no retry sleeps.
      libtraci::Simulation::init(port, 0, "localhost", label_);
    } catch (const std::exception& e) {
      process_->kill();
      process_->wait();
      process_.reset();
      if (attempt < 3) continue;
      throw SimError(std::string("cannot connect to SUMO over TraCI: ") + e.what());
    }
    open_ = true;
    return;
  }
}

SumoBridge::~SumoBridge() {
  try {
    close();
  } catch (const std::exception& e) {
    spdlog::warn("event=sumo_close_failed error=\"{}\"", e.what());
  }
}

double SumoBridge::step() {
  if (!open_) throw SimError("the SUMO connection is closed");
  try {
    libtraci::Simulation::switchConnection(label_);
    libtraci::Simulation::step();
    time_s_ = libtraci::Simulation::getTime();
  } catch (const std::exception& e) {
    open_ = false;
    throw SimError(std::string("SUMO connection lost: ") + e.what() + "; end of " + log_.string() + ":" + tail_of(log_));
  }
  return time_s_;
}

void SumoBridge::close() {
  if (open_) {
    open_ = false;
    try {
      libtraci::Simulation::switchConnection(label_);
      libtraci::Simulation::close();
    } catch (const std::exception& e) {
      spdlog::warn("event=sumo_close error=\"{}\"", e.what());
    }
  }
  if (process_) {
    // SUMO exits after close; a hung one is killed rather than waited for forever.
    for (int i = 0; i < 3000 && process_->running(); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    process_->kill();
    const int rc = process_->wait();
    process_.reset();
    if (rc != 0) spdlog::warn("event=sumo_exit status={} log={}", rc, log_.string());
  }
}

}  // namespace corridor::sim
