// A SUMO network loaded once for many runs: the parsed net, its road graph with SUMO's ids, and
// its traffic lights as signal plans for the preemption engine.
#pragma once

#include <filesystem>
#include <string>
#include <unordered_map>
#include <vector>

#include "maps/sumo_graph.hpp"
#include "maps/sumo_net.hpp"
#include "sim/scenario_builder.hpp"

namespace corridor::sim {

struct SumoScenario {
  std::string name;
  std::filesystem::path dir;  // scenario files and run outputs
  std::filesystem::path net_file;
  maps::SumoNet net;
  maps::SumoGraph graph;
  std::vector<maps::SumoSignalPlan> sumo_plans;
  std::unordered_map<NodeId, maps::SignalPlan> plans;
  std::unordered_map<NodeId, const maps::SumoSignalPlan*> sumo_plan_of;
  std::unordered_map<std::string, std::vector<maps::SumoTlPhase>> tls_phases;
  std::optional<SumoConfig> config;  // a user's scenario: SUMO runs its configuration
};

// Throws MapLoadError / SimError for an unreadable or unusable net. With a configuration, the
// traffic-light programs of its additional files replace the net's (SUMO runs the last program
// loaded for a light), so that the normal programs preemption restores are the scenario's own.
std::unique_ptr<SumoScenario> load_sumo_scenario(const ScenarioNet& net);

}  // namespace corridor::sim
