// The signals of a map, as a controller sees them: the plan at every node a signal controls, and
// the signals themselves, one per controller. On an OSM map each signalized node is its own signal;
// a SUMO traffic light controls several stop lines (and, joined, several junctions) and is one
// signal, keyed by its lowest stop-line node and named by its tls id. Routing and the preemption
// engine's crossings read `plans`; the engine, the controllers and the API hold `signals`.
#pragma once

#include <string>
#include <unordered_map>

#include "maps/signal_plan.hpp"

namespace corridor::maps {

struct SignalMap {
  std::unordered_map<NodeId, SignalPlan> plans;    // by controlled node
  std::unordered_map<NodeId, SignalPlan> signals;  // by signal key
  std::unordered_map<NodeId, NodeId> signal_of;    // controlled node -> its signal's key (absent: itself)
  std::unordered_map<NodeId, std::string> names;   // signal key -> SUMO tls id; absent on OSM maps

  // The key of the signal controlling `node` (the node itself when it is its own).
  [[nodiscard]] NodeId key(NodeId node) const {
    const auto it = signal_of.find(node);
    return it == signal_of.end() ? node : it->second;
  }
};

// Every plan its own signal.
[[nodiscard]] SignalMap signal_map_of(std::unordered_map<NodeId, SignalPlan> plans);

}  // namespace corridor::maps
