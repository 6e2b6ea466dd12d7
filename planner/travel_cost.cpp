#include "planner/travel_cost.hpp"

#include <cmath>
#include <string>

namespace corridor::planner {

TravelCost::TravelCost(const maps::RoadGraph& graph, const CostOverlay& overlay, VehicleProfile vehicle)
    : graph_(&graph), overlay_(&overlay), vmax_mps_(vehicle.vmax_mps) {
  if (!(vehicle.vmax_mps > 0.0) || !std::isfinite(vehicle.vmax_mps)) {
    throw CostUpdateError("vehicle max speed must be a positive number, got " + std::to_string(vehicle.vmax_mps) +
                          " m/s");
  }
  if (overlay.edge_count() != graph.edge_count() || overlay.node_count() != graph.node_count()) {
    throw CostUpdateError("cost overlay was built for another graph");
  }
}

double TravelCost::partial_time_s(EdgeId e, double from_m, double to_m) const {
  const double length = graph_->length_m(e);
  from_m = std::clamp(from_m, 0.0, length);
  to_m = std::clamp(to_m, 0.0, length);
  const double fraction = (to_m - from_m) / length;
  // 0 × ∞ (no distance left on a closed edge) is 0: the vehicle is already there.
  return fraction <= 0.0 ? 0.0 : fraction * edge_time_s(e);
}

}  // namespace corridor::planner
