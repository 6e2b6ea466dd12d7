// The closed loop over libtraci: a sumo process on a free port (SumoBridge).
#include <libsumo/libtraci.h>

#include "sim/closed_loop_run.hpp"

namespace corridor::sim {
namespace {

struct TraciApi {
  using Simulation = libtraci::Simulation;
  using Edge = libtraci::Edge;
  using Lane = libtraci::Lane;
  using LaneArea = libtraci::LaneArea;
  using InductionLoop = libtraci::InductionLoop;
  using Route = libtraci::Route;
  using Vehicle = libtraci::Vehicle;
  using TrafficLight = libtraci::TrafficLight;
};

}  // namespace

ClosedLoopResult run_closed_loop_traci(const SumoScenario& scenario, const ClosedLoopConfig& config) {
  return detail::run_loop<TraciApi, SumoBridge>(scenario, config);
}

}  // namespace corridor::sim
