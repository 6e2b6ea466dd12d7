// The planner's cost model: edge travel time from length, speed, vehicle max speed, congestion and
// queue delay; node crossing delay; and the admissible landmark (ALT) heuristic.
#pragma once

#include <algorithm>

#include "maps/road_graph.hpp"
#include "planner/cost.hpp"
#include "planner/cost_overlay.hpp"

namespace corridor::planner {

struct VehicleProfile {
  double vmax_mps = 120.0 / 3.6;
};

// A point on a directed edge, `offset_m` from its tail in the edge's length units.
struct EdgePoint {
  EdgeId edge;
  double offset_m = 0.0;
};

class TravelCost {
 public:
  // Throws CostUpdateError when vmax is not a positive finite speed.
  TravelCost(const maps::RoadGraph& graph, const CostOverlay& overlay, VehicleProfile vehicle);

  // length / min(edge speed, vmax) × congestion factor, and never below that free-flow time:
  // congestion only slows a vehicle down. A factor below 1 (traffic measured faster than the legal
  // speed) counts as 1, which keeps free flow at the legal speed a lower bound of every edge's
  // cost, as the landmark heuristic requires.
  [[nodiscard]] double running_time_s(EdgeId e) const {
    const double free_flow = graph_->length_m(e) / std::min(graph_->speed_mps(e), vmax_mps_);
    return free_flow * std::max(overlay_->edge(e).congestion_factor, 1.0);
  }
  [[nodiscard]] double edge_time_s(EdgeId e) const { return add_cost(running_time_s(e), overlay_->edge(e).queue_delay_s); }
  [[nodiscard]] double node_delay_s(NodeId v) const { return overlay_->node_delay_s(v); }

  // Crossing the tail intersection, then driving the edge: the weight of a graph edge. Folding the
  // node cost into its out-edges makes node costs exact for every path through the node.
  [[nodiscard]] double transit_s(EdgeId e) const { return add_cost(node_delay_s(graph_->tail(e)), edge_time_s(e)); }

  // Driving from offset `from_m` to `to_m` on e. The queue delay is spread along the edge in
  // proportion to distance: a position fix cannot tell whether a vehicle near the stop line is
  // before or after the queue, and charging the whole delay to every position short of the end
  // would charge a vehicle at the stop line for a queue it is already through.
  [[nodiscard]] double partial_time_s(EdgeId e, double from_m, double to_m) const;

  // A lower bound on the cost of any path from a to b, consistent over every arc: the graph's
  // landmark bound on free-flow time (maps/landmarks.hpp).
  [[nodiscard]] double lower_bound_s(NodeId a, NodeId b) const { return graph_->landmark_bound_s(a, b); }

  [[nodiscard]] const maps::RoadGraph& graph() const { return *graph_; }
  [[nodiscard]] const CostOverlay& overlay() const { return *overlay_; }
  [[nodiscard]] double vmax_mps() const { return vmax_mps_; }

 private:
  const maps::RoadGraph* graph_;
  const CostOverlay* overlay_;
  double vmax_mps_;
};

}  // namespace corridor::planner
