// One SUMO process driven over TraCI (libtracicpp): started on a free port, connected without
// retry sleeps, stepped, and shut down (or killed) when the bridge goes away. Values read every
// step come from subscriptions.
#pragma once

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "sim/process.hpp"

namespace corridor::sim {

struct SumoLaunch {
  // A user's configuration, run with -c: its net, demand, programs and options stand, and only the
  // options below override them. Empty: the net and routes below.
  std::filesystem::path config;
  double scale = 1.0;  // SUMO's --scale: the demand's multiplier
  // Further options set for this run, such as a configuration's outputs sent to the run directory.
  std::vector<std::pair<std::string, std::string>> options;
  std::filesystem::path net;
  std::vector<std::filesystem::path> routes;
  std::vector<std::filesystem::path> additional;
  std::filesystem::path tripinfo;  // written at the end; empty for none
  std::filesystem::path log;       // SUMO's own output
  double step_length_s = 1.0;
  double end_s = 3600.0;
  std::uint64_t seed = 1;
  std::string sumo_binary = "sumo";
};

// The sumo command line for a launch; with a port, SUMO waits there for one TraCI client.
std::vector<std::string> sumo_command(const SumoLaunch& launch, std::optional<int> port);

class SumoBridge {
 public:
  // Throws SimError when SUMO does not start or listen within 60 s, with the end of its log.
  explicit SumoBridge(const SumoLaunch& launch);
  ~SumoBridge();
  SumoBridge(const SumoBridge&) = delete;
  SumoBridge& operator=(const SumoBridge&) = delete;

  // Advances one step; returns the simulation time after it. Throws SimError if SUMO is gone.
  double step();
  // Ends the simulation so that SUMO writes its outputs, and waits for the process.
  void close();

  [[nodiscard]] double time_s() const { return time_s_; }
  [[nodiscard]] const std::filesystem::path& log() const { return log_; }

 private:
  std::unique_ptr<ChildProcess> process_;
  std::filesystem::path log_;
  std::string label_;
  double time_s_ = 0.0;
  bool open_ = false;
};

}  // namespace corridor::sim
