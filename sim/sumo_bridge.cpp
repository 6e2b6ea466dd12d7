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

std::vector<std::string> sumo_command(const SumoLaunch& launch, std::optional<int> port) {
  std::vector<std::string> cmd{launch.sumo_binary};
  if (launch.config.empty()) {
    cmd.insert(cmd.end(), {"-n", launch.net.string()});
  } else {
    cmd.insert(cmd.end(), {"-c", launch.config.string()});
  }
  if (launch.scale != 1.0) cmd.insert(cmd.end(), {"--scale", fmt::format("{:g}", launch.scale)});
  for (const auto& [name, value] : launch.options) cmd.insert(cmd.end(), {"--" + name, value});
  if (!launch.routes.empty()) cmd.insert(cmd.end(), {"-r", join_paths(launch.routes)});
  if (!launch.additional.empty()) cmd.insert(cmd.end(), {"-a", join_paths(launch.additional)});
  if (!launch.tripinfo.empty()) {
    cmd.insert(cmd.end(), {"--tripinfo-output", launch.tripinfo.string(), "--tripinfo-output.write-unfinished", "true"});
  }
  cmd.insert(cmd.end(), {"--step-length", fmt::format("{:g}", launch.step_length_s), "--end", fmt::format("{:g}", launch.end_s),
                         "--seed", std::to_string(launch.seed), "--no-step-log", "true", "--duration-log.disable", "true",
                         "--collision.action", "warn"});
  // A user's scenario keeps its own teleport and route-error settings.
  if (launch.config.empty()) cmd.insert(cmd.end(), {"--time-to-teleport", "300", "--ignore-route-errors", "true"});
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
