#include "planner/search_space.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace corridor::planner {

SearchSpace::SearchSpace(const TravelCost& cost, std::vector<EdgePoint> starts, std::vector<EdgePoint> goals)
    : cost_(&cost), node_count_(cost.graph().node_count()) {
  normalize(goals, "goal");
  goals_ = std::move(goals);
  goal_pos_ = cost.graph().point_along(goals_.front().edge, goals_.front().offset_m);
  set_starts(std::move(starts));
}

void SearchSpace::set_starts(std::vector<EdgePoint> starts) {
  normalize(starts, "start");
  starts_ = std::move(starts);
  start_pos_ = cost_->graph().point_along(starts_.front().edge, starts_.front().offset_m);
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
  }
}

}  // namespace corridor::planner
