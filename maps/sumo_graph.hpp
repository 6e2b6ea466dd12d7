// A SUMO network as an edge-based RoadGraph for one vehicle class, so that SUMO's turn rules and
// lane permissions hold in every route: each SUMO edge the class may use has its stop line as a
// graph node, and each SUMO connection (from edge -> to edge) whose lanes admit the class is a graph
// edge that drives the whole `to` edge. A U-turn, a turn SUMO does not connect, a bus-only lane or
// a connection only other classes may take is simply not in the graph. SUMO edges that nothing
// leads into get an extra entry node at their start.
#pragma once

#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "maps/road_graph.hpp"
#include "maps/signal_map.hpp"
#include "maps/sumo_net.hpp"

namespace corridor::maps {

struct SumoGraph {
  RoadGraph graph;
  SumoClasses vehicle_class = kAllSumoClasses;  // the class the graph was built for
  std::vector<std::string> sumo_edge_of_arc;                     // by EdgeId: the SUMO edge it drives
  std::vector<std::string> sumo_edge_of_node;                    // by NodeId: whose stop line (or entry) it is
  std::unordered_map<std::string, std::vector<EdgeId>> arcs_onto;  // SUMO edge -> the graph edges driving it
  std::unordered_map<std::string, NodeId> stop_line;              // SUMO edge -> its stop-line node

  // The graph edges that put a vehicle on `sumo_edge`; empty for an unknown or internal edge.
  [[nodiscard]] std::span<const EdgeId> arcs(const std::string& sumo_edge) const;
};

// The graph for vehicles of SUMO class `vehicle_class` ("emergency" unless the run's vehicle type
// says otherwise). Length, speed and shape come from the first lane the class may use. Throws
// MapLoadError for an unknown class, or when the class can drive no edge of the net.
SumoGraph build_sumo_graph(const SumoNet& net, std::string_view vehicle_class = "emergency");

// The traffic lights as signal plans keyed by graph node: every stop line a light controls gets
// that light's plan, with each movement (SUMO link) tied to the graph edge of its connection.
// `tls_of` receives each node's index into `plans`.
std::unordered_map<NodeId, SignalPlan> plans_by_node(const SumoGraph& graph, const SumoNet& net,
                                                     const std::vector<SumoSignalPlan>& plans,
                                                     std::unordered_map<NodeId, std::size_t>* tls_of = nullptr);

// The lights as signals: plans_by_node's plan at every stop line, and one signal per light keyed by
// its lowest stop-line node and named by its tls id. `tls_of` receives each stop line's index into `plans`.
SignalMap sumo_signal_map(const SumoGraph& graph, const SumoNet& net, const std::vector<SumoSignalPlan>& plans,
                          std::unordered_map<NodeId, std::size_t>* tls_of = nullptr);

}  // namespace corridor::maps
