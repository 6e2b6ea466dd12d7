#include "planner/search_space.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace corridor::planner {

SearchSpace::SearchSpace(const TravelCost& cost, std::vector<EdgePoint> starts, std::vector<EdgePoint> goals)
    : cost_(&cost), turns_(&cost.graph().turns()), turn_vertices_(turns_->vertex_count()) {
  normalize(goals, "goal");
  goals_ = std::move(goals);
  for (const EdgePoint& t : goals_) goal_tails_.push_back(cost.graph().tail(t.edge));
  std::sort(goal_tails_.begin(), goal_tails_.end());
  goal_tails_.erase(std::unique(goal_tails_.begin(), goal_tails_.end()), goal_tails_.end());
  set_starts(std::move(starts));
}

void SearchSpace::set_starts(std::vector<EdgePoint> starts) {
  normalize(starts, "start");
  starts_ = std::move(starts);
  start_heads_.clear();
  for (const EdgePoint& s : starts_) start_heads_.push_back(cost_->graph().head(s.edge));
  std::sort(start_heads_.begin(), start_heads_.end());
  start_heads_.erase(std::unique(start_heads_.begin(), start_heads_.end()), start_heads_.end());
}

double SearchSpace::move_starts(std::vector<EdgePoint> starts) {
  old_heads_.assign(start_heads_.begin(), start_heads_.end());
  set_starts(std::move(starts));
  return start_shift_s(old_heads_);
}

double SearchSpace::start_shift_s(std::span<const NodeId> old_heads) const {
  double shift = 0.0;
  for (NodeId b : start_heads_) {
    double nearest = kInfCost;
    for (NodeId a : old_heads) nearest = std::min(nearest, cost_->lower_bound_s(a, b));
    shift = std::max(shift, nearest);
  }
  return shift;
}

Route SearchSpace::route_along(std::vector<EdgeId> edges) const {
  EdgePoint start = starts_.front();
  EdgePoint goal = goals_.front();
  if (edges.empty()) {
    Route none;
    none.start = start;
    none.goal = goal;
    return none;
  }
  for (const EdgePoint& p : starts_) {
    if (p.edge == edges.front()) start = p;
  }
  for (const EdgePoint& p : goals_) {
    if (p.edge == edges.back()) goal = p;
  }
  return make_route(*cost_, start, std::move(edges), goal);
}

bool SearchSpace::is_start_edge(EdgeId e) const {
  for (const EdgePoint& s : starts_) {
    if (s.edge == e) return true;
  }
  return false;
}

void SearchSpace::normalize(std::vector<EdgePoint>& points, const char* what) const {
  if (points.empty()) throw std::invalid_argument(std::string("a route needs at least one ") + what + " point");
  for (EdgePoint& p : points) {
    if (!p.edge.valid() || p.edge.index() >= cost_->graph().edge_count()) {
      throw std::invalid_argument(std::string(what) + " point names unknown edge " + std::to_string(p.edge.v));
    }
    if (!std::isfinite(p.offset_m)) throw std::invalid_argument(std::string(what) + " point offset is not finite");
    p.offset_m = std::clamp(p.offset_m, 0.0, cost_->graph().length_m(p.edge));
    if (p.turn_vertex != EdgePoint::kPlainEdge &&
        (p.turn_vertex >= turns_->vertex_count() || turns_->edge_of(p.turn_vertex) != p.edge)) {
      throw std::invalid_argument(std::string(what) + " point names turn-graph state " + std::to_string(p.turn_vertex) +
                                  ", which is not on edge " + std::to_string(p.edge.v));
    }
  }
}

}  // namespace corridor::planner
