// The preemption engine's test rigs: a four-legged signalized junction with its default plan, the
// in-memory controller and a safety monitor watching it. Shared by the engine's test files.
#pragma once

#include <cstdint>
#include <unordered_map>
#include <vector>

#include "maps/graph_builder.hpp"
#include "maps/intersection_geometry.hpp"
#include "preemption/engine.hpp"
#include "preemption/safety_monitor.hpp"
#include "preemption/simulated_signal_controller.hpp"

namespace corridor::preemption {

// A four-legged signalized junction C at the origin, with legs 200 m to the N, E, S and W.
inline maps::RoadGraph plus_junction() {
  maps::GraphBuildInput in;
  in.origin = {47.0, 9.5};
  in.node_pos = {{0, 0}, {0, 200}, {200, 0}, {0, -200}, {-200, 0}};
  for (std::int64_t i = 0; i < 5; ++i) in.node_osm.push_back(OsmNodeId{i + 1});
  in.node_signalized = {1, 0, 0, 0, 0};
  for (std::uint32_t leg = 1; leg <= 4; ++leg) {
    maps::RoadSegment s;
    s.from = 0;
    s.to = leg;
    s.first_point = static_cast<std::uint32_t>(in.points.size());
    in.points.push_back(in.node_pos[0]);
    in.points.push_back(in.node_pos[leg]);
    s.last_point = s.first_point + 1;
    s.forward_speed_mps = s.backward_speed_mps = 14.0f;
    s.way = OsmWayId{leg};
    in.segments.push_back(s);
  }
  return maps::build_road_graph(in);
}

inline EdgeId edge(const maps::RoadGraph& g, std::int64_t from_osm, std::int64_t to_osm) {
  for (EdgeId e : g.edges()) {
    if (g.osm_node(g.tail(e)).v == from_osm && g.osm_node(g.head(e)).v == to_osm) return e;
  }
  return kInvalidEdge;
}

inline constexpr std::int64_t kC = 1, kN = 2, kE = 3, kS = 4, kW = 5;

struct Rig {
  maps::RoadGraph graph = plus_junction();
  std::unordered_map<NodeId, maps::SignalPlan> plans = maps::default_signal_plans(graph);
  SimulatedSignalController controller{plans, 0.0};
  SafetyMonitor monitor;
  PreemptionEngine engine{graph, plans, controller};
  NodeId c = graph.head(edge(graph, kN, kC));

  Rig() {
    for (const auto& [node, plan] : plans) monitor.watch(plan, controller.lights(node), 0.0);
    controller.set_observer([this](NodeId n, const std::vector<Light>& l, double t) { monitor.observe(n, l, t); });
  }
  Crossing crossing(std::int64_t from, std::int64_t to, double arrival_s) {
    return {c, edge(graph, from, kC), edge(graph, kC, to), arrival_s};
  }
  void run_until(double t) {
    controller.advance(t);
    engine.tick(t);
  }
  const maps::SignalPlan& plan() { return plans.at(c); }
};

}  // namespace corridor::preemption
