// Which movement of an intersection's signal plan a vehicle makes, given the edge it arrives on and
// the edge it leaves by. Shared by the preemption engine (which phase to call) and the route costs
// (which movement's green share a turn waits on), so the two never disagree about a turn.
#pragma once

#include <cstddef>
#include <optional>

#include "maps/road_graph.hpp"
#include "maps/signal_plan.hpp"

namespace corridor::preemption {

// The movement whose edge is `out_edge` (plans that name their movements' edges, as SUMO's do);
// else the one between the compass sides of the approach and the exit; else, for a U-turn, the
// approach's left turn (NEMA plans are for right-hand traffic), and for a leg the plan merged the
// approach's first movement, which stands for it (every phase choice depends on the approach).
// nullopt when the plan has no movement from that approach.
std::optional<std::size_t> plan_movement(const maps::RoadGraph& graph, const maps::SignalPlan& plan, EdgeId in_edge,
                                         EdgeId out_edge);

}  // namespace corridor::preemption
