// Compass legs of intersections from the road geometry: which way a route enters and leaves a node,
// and the default NEMA plan of every signalized OSM intersection that has no plan of its own.
#pragma once

#include <unordered_map>

#include "maps/road_graph.hpp"
#include "maps/signal_plan.hpp"

namespace corridor::maps {

// The side of head(in_edge) that traffic on in_edge comes from ("from North" = arriving southbound).
Compass approach_side(const RoadGraph& graph, EdgeId in_edge);
// The side of tail(out_edge) that traffic on out_edge leaves by.
Compass exit_side(const RoadGraph& graph, EdgeId out_edge);
// Bit per Compass value for every side that has a road.
std::uint8_t legs_of(const RoadGraph& graph, NodeId node);

// One NEMA plan per signalized node, keyed by node.
std::unordered_map<NodeId, SignalPlan> default_signal_plans(const RoadGraph& graph, const NemaTiming& timing = {});

}  // namespace corridor::maps
