#include "ntcip/virtual_agents.hpp"

#include <algorithm>
#include <stdexcept>

namespace corridor::ntcip {
namespace {

std::vector<NodeId> sorted_keys(const maps::SignalMap& signals) {
  std::vector<NodeId> keys;
  for (const auto& [key, plan] : signals.signals) keys.push_back(key);
  std::sort(keys.begin(), keys.end());
  return keys;
}

std::vector<maps::Compass> approaches(const maps::SignalPlan& plan) {
  std::vector<maps::Compass> out;
  for (maps::Compass c : {maps::Compass::north, maps::Compass::east, maps::Compass::south, maps::Compass::west}) {
    if (std::any_of(plan.movements.begin(), plan.movements.end(), [&](const maps::Movement& m) { return m.from == c; })) out.push_back(c);
  }
  return out;
}

}  // namespace

std::vector<ControllerConfig> virtual_manifest(const maps::RoadGraph& graph, const maps::SignalMap& signals,
                                               const VirtualAgentsConfig& config) {
  const std::vector<NodeId> keys = sorted_keys(signals);
  if (static_cast<std::size_t>(config.first_port) + keys.size() > 65536) {
    throw std::invalid_argument("the map has " + std::to_string(keys.size()) + " signals: ports from " +
                                std::to_string(config.first_port) + " would run past 65535");
  }
  std::vector<ControllerConfig> out;
  for (std::size_t i = 0; i < keys.size(); ++i) {
    const maps::SignalPlan& plan = signals.signals.at(keys[i]);
    ControllerConfig c;
    if (const auto name = signals.names.find(keys[i]); name != signals.names.end()) {
      c.tls_id = name->second;
    } else {
      c.osm_node_id = graph.osm_node(keys[i]).v;
    }
    c.id = c.tls_id ? *c.tls_id : std::to_string(*c.osm_node_id);
    c.host = config.host;
    c.port = static_cast<std::uint16_t>(config.first_port + i);
    c.snmp.read_community = config.security.read_community;
    c.snmp.write_community = config.security.write_community;
    const std::vector<maps::Compass> sides = approaches(plan);
    for (std::size_t k = 0; k < sides.size(); ++k) c.preempts.push_back({static_cast<std::uint32_t>(k + 1), sides[k], std::nullopt});
    for (std::size_t m = 0; m < plan.movements.size(); ++m) {
      c.phases.push_back({static_cast<std::uint32_t>(m + 1), plan.movements[m].label()});
      for (std::size_t n = m + 1; n < plan.movements.size(); ++n) {
        if (plan.conflicts(m, n)) c.conflicts.emplace_back(static_cast<std::uint32_t>(m + 1), static_cast<std::uint32_t>(n + 1));
      }
    }
    c.mode = PriorityMode::by_priority;
    c.description = "Corridor virtual NTCIP 1202 controller, " + (c.tls_id ? "SUMO light " + *c.tls_id : "OSM node " + c.id);
    out.push_back(std::move(c));
  }
  return out;
}

VirtualAgents::VirtualAgents(const maps::RoadGraph& graph, const maps::SignalMap& signals, preemption::SignalController& controller,
                             VirtualAgentsConfig config, double now_s)
    : manifest_(virtual_manifest(graph, signals, config)), agent_(config.security) {
  const std::vector<NodeId> keys = sorted_keys(signals);
  for (std::size_t i = 0; i < keys.size(); ++i) {
    std::vector<PreemptInput> inputs;
    for (const PreemptWiring& w : manifest_[i].preempts) inputs.push_back({w.number, w.approach, std::nullopt});
    intersections_.push_back(std::make_unique<VirtualIntersection>(keys[i], signals.signals.at(keys[i]), std::move(inputs), controller,
                                                                   manifest_[i].description, config.timing));
    intersections_.back()->step(now_s);
    agent_.serve(config.host, manifest_[i].port, *intersections_.back());
  }
}

void VirtualAgents::poll(int timeout_ms, double now_s) {
  agent_.poll(timeout_ms, now_s);
  for (auto& x : intersections_) x->step(now_s);
}

}  // namespace corridor::ntcip
