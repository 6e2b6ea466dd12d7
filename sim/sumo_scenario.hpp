// A SUMO network loaded once for many runs: the parsed net, its road graph with SUMO's ids, and
// its traffic lights as signal plans for the preemption engine.
#pragma once

#include <filesystem>
#include <set>
#include <string>
#include <unordered_map>
#include <vector>

#include "maps/sumo_graph.hpp"
#include "maps/sumo_net.hpp"
#include "sim/scenario_builder.hpp"
#include "sim/sumo_options.hpp"

namespace corridor::sim {

struct SumoScenario {
  std::string name;
  std::string ev_vclass = "emergency";  // the SUMO class the EV drives as, and the graph is built for
  std::filesystem::path dir;  // scenario files and run outputs
  std::filesystem::path net_file;
  maps::SumoNet net;
  maps::SumoGraph graph;
  std::vector<maps::SumoSignalPlan> sumo_plans;
  std::unordered_map<NodeId, maps::SignalPlan> plans;  // every stop line a light controls
  // One plan per SUMO traffic light, keyed by its lowest stop-line node: what the preemption engine
  // and the signal controller hold, so that claims on one light from different approaches are
  // arbitrated against each other and one controller alone sets the light's state.
  std::unordered_map<NodeId, maps::SignalPlan> signal_plans;
  std::unordered_map<NodeId, NodeId> signal_node;  // stop-line node -> its light's key in signal_plans
  std::unordered_map<NodeId, const maps::SumoSignalPlan*> sumo_plan_of;
  std::unordered_map<std::string, std::vector<maps::SumoTlPhase>> tls_phases;
  std::set<std::string> actuated_tls;  // lights whose programs SUMO times itself
  std::optional<SumoConfig> config;  // a user's scenario: SUMO runs its configuration
  SumoOptionCatalog sumo_options;    // the installed SUMO's options, for each run's configuration
};

// The light's key (signal_plans) of a stop-line node; the node itself when no light controls it.
[[nodiscard]] inline NodeId signal_of(const SumoScenario& s, NodeId stop_line) {
  const auto it = s.signal_node.find(stop_line);
  return it == s.signal_node.end() ? stop_line : it->second;
}

// Throws MapLoadError / SimError for an unreadable or unusable net. With a configuration, the
// traffic-light programs of its additional files replace the net's (SUMO runs the last program
// loaded for a light), so that the normal programs preemption restores are the scenario's own. The
// graph admits what SUMO admits for an EV of class `ev_vclass`: its routes are ones SUMO accepts.
std::unique_ptr<SumoScenario> load_sumo_scenario(const ScenarioNet& net, const std::string& ev_vclass = "emergency");

}  // namespace corridor::sim
