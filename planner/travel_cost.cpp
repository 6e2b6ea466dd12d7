#include "planner/travel_cost.hpp"

#include <cmath>
#include <numbers>
#include <string>

namespace corridor::planner {

TravelCost::TravelCost(const maps::RoadGraph& graph, const CostOverlay& overlay, VehicleProfile vehicle)
    : graph_(&graph), overlay_(&overlay), profile_(std::move(vehicle)) {
  if (!(profile_.vmax_mps > 0.0) || !std::isfinite(profile_.vmax_mps)) {
    throw CostUpdateError("vehicle max speed must be a positive number, got " + std::to_string(profile_.vmax_mps) + " m/s");
  }
  validate(profile_);
  if (overlay.edge_count() != graph.edge_count() || overlay.node_count() != graph.node_count()) {
    throw CostUpdateError("cost overlay was built for another graph");
  }
  scaled_speeds_ = std::any_of(profile_.speed_factor.begin(), profile_.speed_factor.end(), [](double f) { return f != 1.0; });
  // A turn of θ costs turn_penalty × (1 − cos θ) / 2: nothing straight on, half at a right angle,
  // all of it turning back. A turn of more than 30° towards the side of oncoming traffic (left where
  // traffic keeps right) waits for a gap in it as well.
  const double crossing_sign = graph.left_hand_traffic() ? 1.0 : -1.0;
  for (int a = -180; a <= 180; ++a) {
    const double theta = a * std::numbers::pi / 180.0;
    double c = profile_.turn_penalty_s * (1.0 - std::cos(theta)) / 2.0;
    if (a * crossing_sign > 30.0) c += profile_.crossing_penalty_s;
    angle_cost_s_[static_cast<std::size_t>(a + 180)] = c;
  }
  for (const maps::EdgeLimit& l : graph.edge_limits()) {
    const bool too_tall = l.max_height_m > 0 && profile_.height_m > l.max_height_m;
    const bool too_wide = l.max_width_m > 0 && profile_.width_m > l.max_width_m;
    const bool too_heavy = l.max_weight_t > 0 && profile_.weight_t > l.max_weight_t;
    if (!too_tall && !too_wide && !too_heavy) continue;
    if (blocked_.empty()) blocked_.assign(graph.edge_count(), 0);
    blocked_[l.edge.index()] = 1;
  }
  if (!profile_.ferries) {
    for (EdgeId e : graph.edges()) {
      if (!graph.is_ferry(e)) continue;
      if (blocked_.empty()) blocked_.assign(graph.edge_count(), 0);
      blocked_[e.index()] = 1;
    }
  }
}

std::pair<double, std::uint32_t> TravelCost::turn_onto(std::uint32_t from, EdgeId next) const {
  const auto& t = graph_->turns();
  std::pair<double, std::uint32_t> best{kInfCost, next.v};
  const EdgeId in = t.edge_of(from);
  for (const maps::TurnArc& a : t.arcs_out(from)) {
    if (t.edge_of(a.other) == next) {
      const double c = turn_cost_s(in, a, next);
      if (c < best.first || best.first >= kInfCost) best = {c, a.other};
    }
  }
  return best;
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
