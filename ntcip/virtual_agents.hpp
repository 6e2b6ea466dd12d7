// Virtual NTCIP 1202 controllers for every signal of a map: one agent per signalized
// intersection, on consecutive UDP ports, each a VirtualIntersection over a SignalController that
// runs the map's normal programs (the in-memory one for `corridor signal-agent`, SUMO's lights for
// `corridor sim --ntcip`). Their manifest is a valid controllers file for `corridor serve`.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "maps/road_graph.hpp"
#include "maps/signal_map.hpp"
#include "ntcip/controllers_file.hpp"
#include "ntcip/snmp_agent.hpp"
#include "ntcip/virtual_intersection.hpp"

namespace corridor::ntcip {

struct VirtualAgentsConfig {
  std::string host = "127.0.0.1";
  unsigned short first_port = 16100;
  AgentSecurity security;
  VirtualTiming timing;
};

// What the agents serve, in port order: one entry per signal (sorted by its key), its preempt
// inputs one per approach (N, E, S, W as present, numbered from 1), its phases one per plan
// movement (NTCIP phase k+1 is movement k) and the pairs of phases that conflict. Throws
// std::invalid_argument when the ports would run past 65535.
std::vector<ControllerConfig> virtual_manifest(const maps::RoadGraph& graph, const maps::SignalMap& signals,
                                               const VirtualAgentsConfig& config);

class VirtualAgents {
 public:
  // `controller` holds every signal of `signals` (by key); all must outlive the agents. Throws
  // SnmpError when a port cannot be bound.
  VirtualAgents(const maps::RoadGraph& graph, const maps::SignalMap& signals, preemption::SignalController& controller,
                VirtualAgentsConfig config, double now_s);

  [[nodiscard]] const std::vector<ControllerConfig>& manifest() const { return manifest_; }
  // Answers what arrived within timeout_ms, and moves every intersection's logic to now_s.
  void poll(int timeout_ms, double now_s);
  [[nodiscard]] const std::vector<std::unique_ptr<VirtualIntersection>>& intersections() const { return intersections_; }
  [[nodiscard]] std::size_t requests_answered() const { return agent_.requests_answered(); }

 private:
  std::vector<ControllerConfig> manifest_;
  SnmpAgent agent_;
  std::vector<std::unique_ptr<VirtualIntersection>> intersections_;
};

}  // namespace corridor::ntcip
