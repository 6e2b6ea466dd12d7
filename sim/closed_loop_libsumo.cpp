// The closed loop with SUMO in this process (libsumo): no socket and no second process, one
// simulation at a time per process (experiment runs are forked children).
#include <libsumo/libsumo.h>

#include "sim/closed_loop_run.hpp"

namespace corridor::sim {
namespace {

struct LibsumoApi {
  using Simulation = libsumo::Simulation;
  using Edge = libsumo::Edge;
  using Lane = libsumo::Lane;
  using LaneArea = libsumo::LaneArea;
  using InductionLoop = libsumo::InductionLoop;
  using Route = libsumo::Route;
  using Vehicle = libsumo::Vehicle;
  using TrafficLight = libsumo::TrafficLight;
};

// Starts SUMO in-process on the run's configuration.
class LibsumoSession {
 public:
  explicit LibsumoSession(const SumoLaunch& launch) {
    // The run's configuration sends SUMO's messages to the run's log, as the socket bridge does.
    const std::vector<std::string> cmd = sumo_command(launch, std::nullopt);
    try {
      libsumo::Simulation::start(cmd);
    } catch (const std::exception& e) {
      std::error_code ec;
      const bool logged = std::filesystem::file_size(launch.log, ec) > 0 && !ec;
      throw SimError(std::string("libsumo could not start the simulation: ") + e.what() + "; " +
                     (logged ? "see " + launch.log.string() : "SUMO wrote its reason on standard error") + " (configuration " +
                     launch.run_config.string() + ")");
    }
    open_ = true;
  }
  ~LibsumoSession() {
    try {
      close();
    } catch (const std::exception& e) {
      spdlog::warn("event=libsumo_close_failed error=\"{}\"", e.what());
    }
  }
  LibsumoSession(const LibsumoSession&) = delete;
  LibsumoSession& operator=(const LibsumoSession&) = delete;

  double step() {
    libsumo::Simulation::step();
    return libsumo::Simulation::getTime();
  }
  void close() {
    if (!open_) return;
    open_ = false;
    libsumo::Simulation::close();
  }

 private:
  bool open_ = false;
};

}  // namespace

ClosedLoopResult run_closed_loop_libsumo(const SumoScenario& scenario, const ClosedLoopConfig& config) {
  return detail::run_loop<LibsumoApi, LibsumoSession>(scenario, config);
}

}  // namespace corridor::sim
