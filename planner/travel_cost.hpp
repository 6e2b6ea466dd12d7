// The planner's cost model: edge travel time from length, speed, the vehicle's profile, congestion
// and queue delay; node crossing delay; the cost of each turn (angle, crossing traffic, U-turn,
// restrictions); and the admissible landmark (ALT) heuristic.
#pragma once

#include <algorithm>
#include <array>
#include <vector>

#include "maps/road_graph.hpp"
#include "planner/cost.hpp"
#include "planner/cost_overlay.hpp"
#include "planner/vehicle_profile.hpp"

namespace corridor::planner {

// A point on a directed edge, `offset_m` from its tail in the edge's length units.
struct EdgePoint {
  EdgeId edge;
  double offset_m = 0.0;
  // The vehicle's state in the turn graph (maps/turn_graph.hpp) while on `edge`: a copy of the edge
  // when a via-way restriction has to remember how the vehicle got onto it. kPlainEdge: the edge's
  // own vertex (where it came from does not matter, or is not known).
  static constexpr std::uint32_t kPlainEdge = std::numeric_limits<std::uint32_t>::max();
  std::uint32_t turn_vertex = kPlainEdge;
  [[nodiscard]] std::uint32_t vertex() const { return turn_vertex == kPlainEdge ? edge.v : turn_vertex; }
};

class TravelCost {
 public:
  // Throws CostUpdateError when vmax is not a positive finite speed, ProfileError for another value
  // out of range.
  TravelCost(const maps::RoadGraph& graph, const CostOverlay& overlay, VehicleProfile vehicle);

  // length / min(edge speed, vmax) × congestion factor, and never below that free-flow time:
  // congestion only slows a vehicle down. A factor below 1 (traffic measured faster than the legal
  // speed) counts as 1, which keeps free flow at the legal speed a lower bound of every edge's
  // cost, as the landmark heuristic requires.
  // An edge the vehicle does not fit (maxheight, maxwidth, maxweight), or a ferry it does not
  // board, costs kInfCost.
  [[nodiscard]] double running_time_s(EdgeId e) const {
    if (!blocked_.empty() && blocked_[e.index()] != 0) return kInfCost;
    double speed = graph_->speed_mps(e);
    if (scaled_speeds_) speed *= profile_.speed_factor[static_cast<std::size_t>(graph_->road_class(e))];
    const double free_flow = graph_->length_m(e) / std::min(speed, profile_.vmax_mps);
    return free_flow * std::max(overlay_->edge(e).congestion_factor, 1.0);
  }
  [[nodiscard]] double edge_time_s(EdgeId e) const { return add_cost(running_time_s(e), overlay_->edge(e).queue_delay_s); }
  // Crossing node v: its delay on the overlay (a signal's expected wait), plus the profile's
  // barrier_delay_s where a gate or toll booth stands on it.
  [[nodiscard]] double node_delay_s(NodeId v) const {
    const double d = overlay_->node_delay_s(v);
    return graph_->stop_at(v) ? add_cost(d, profile_.barrier_delay_s) : d;
  }

  // Crossing the tail intersection, then driving the edge: the weight of a graph edge. Folding the
  // node cost into its out-edges makes node costs exact for every path through the node.
  [[nodiscard]] double transit_s(EdgeId e) const { return add_cost(node_delay_s(graph_->tail(e)), edge_time_s(e)); }

  // The cost of a turn of the edge-based graph (maps/turn_graph.hpp) beyond the edges it joins:
  // kInfCost for a turn a binding restriction forbids or a U-turn the profile does not allow; the
  // U-turn penalty; otherwise the angle's cost plus the crossing penalty for a turn across
  // oncoming traffic. Never negative, so free flow stays a lower bound.
  [[nodiscard]] double turn_s(const maps::TurnArc& a) const {
    if (a.plain()) return angle_cost_s_[static_cast<std::size_t>(a.angle_deg + 180)];
    if ((a.ban_modes() & profile_.restriction_modes) != 0 ||
        ((a.ban_modes_excepted() & profile_.restriction_modes) != 0 && (a.except_classes & profile_.except_classes) == 0)) {
      return kInfCost;
    }
    if (a.uturn()) {
      if (!a.dead_end() && profile_.uturn_policy == UturnPolicy::dead_ends) return kInfCost;
      return profile_.uturn_penalty_s;
    }
    return angle_cost_s_[static_cast<std::size_t>(a.angle_deg + 180)];
  }

  // The whole cost of turning by arc `a` from edge `in` onto edge `out`: turn_s plus the movement's
  // delay on the overlay (its expected signal wait). Every search, the route's ETAs and the trip
  // simulator charge a turn through this (or turn_onto), so they agree to the last bit.
  [[nodiscard]] double turn_cost_s(EdgeId in, const maps::TurnArc& a, EdgeId out) const {
    const double t = turn_s(a);
    return t >= kInfCost ? t : t + overlay_->turn_delay_s(in, out);
  }

  // The turn from turn-graph vertex `from` onto edge `next`: its turn_cost_s (kInfCost when the graph
  // has no such turn) and the vertex it leads to (a copy of next, where a via-way restriction needs it).
  [[nodiscard]] std::pair<double, std::uint32_t> turn_onto(std::uint32_t from, EdgeId next) const;

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
  [[nodiscard]] double vmax_mps() const { return profile_.vmax_mps; }
  [[nodiscard]] const VehicleProfile& profile() const { return profile_; }
  // True when the vehicle does not fit on e.
  [[nodiscard]] bool blocked(EdgeId e) const { return !blocked_.empty() && blocked_[e.index()] != 0; }

 private:
  const maps::RoadGraph* graph_;
  const CostOverlay* overlay_;
  VehicleProfile profile_;
  bool scaled_speeds_;
  std::array<double, 361> angle_cost_s_{};  // by signed angle + 180
  std::vector<std::uint8_t> blocked_;      // by edge; empty when no limit binds the vehicle
};

}  // namespace corridor::planner
