// One SUMO process driven over TraCI (libtracicpp): started on a free port, connected without
// retry sleeps, stepped, and shut down (or killed) when the bridge goes away. Values read every
// step come from subscriptions.
#pragma once

#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "sim/process.hpp"
#include "sim/sumo_options.hpp"

namespace corridor::sim {

struct SumoLaunch {
  // The configuration SUMO reads for this run (write_launch_config writes it): the user's options,
  // if the scenario is a user's, with the run's own below set in it once.
  std::filesystem::path run_config;
  // A user's scenario: its options as its .sumocfg holds them, and the directory that file is in.
  std::vector<SumoOptionValue> user_options;
  std::filesystem::path user_dir;
  // Where a user's output option's file goes (option, value -> path in the run directory).
  std::function<std::string(const std::string&, const std::string&)> redirect_output;
  double scale = 1.0;  // SUMO's --scale: the demand's multiplier
  std::filesystem::path net;
  std::vector<std::filesystem::path> routes;  // the user's, then the run's own
  std::vector<std::filesystem::path> additional;
  std::filesystem::path tripinfo;  // written at the end; empty for none
  std::filesystem::path log;       // SUMO's own output
  double step_length_s = 1.0;
  double end_s = 3600.0;
  std::uint64_t seed = 1;
  std::string sumo_binary = "sumo";
};

// Writes launch.run_config. Throws SimError for an option of the user's that SUMO does not know.
void write_launch_config(const SumoLaunch& launch, const SumoOptionCatalog& catalog);

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
