#include "localizer/fusion/odometry_map_matcher.hpp"

#include "localizer/match/bearing.hpp"

#include <cmath>
#include <numbers>

namespace corridor::localizer {
namespace {


}  // namespace

OdometryMapMatcher::OdometryMapMatcher(const maps::RoadGraph& graph, OdometryMatchConfig config)
    : graph_(graph), config_(config) {}

double OdometryMapMatcher::road_bearing_deg(EdgeId e, double offset_m) const {
  return localizer::road_bearing_deg(graph_, e, offset_m, 3.0);
}

void OdometryMapMatcher::start(EdgeId edge, double offset_m, double heading_deg, double time_s, double sigma_m) {
  edge_ = edge;
  offset_m_ = std::clamp(offset_m, 0.0, graph_.length_m(edge));
  heading_deg_ = heading_deg;
  sigma_m_ = std::max(sigma_m, config_.base_sigma_m);
  last_time_s_ = time_s;
  exits_.clear();
  headings_.clear();
  headings_.emplace_back(time_s, heading_deg);
}

MatchedPoint OdometryMapMatcher::current() const {
  MatchedPoint m;
  if (!edge_.valid()) return m;
  m.matched = true;
  m.edge = edge_;
  m.offset_m = offset_m_;
  m.point = graph_.point_along(edge_, offset_m_);
  m.confidence = std::clamp(config_.base_sigma_m / sigma_m_, 0.0, 1.0);
  return m;
}

void OdometryMapMatcher::decide_exit() {
  // Curve to curve over the metres past the junction: the exit whose bearing there best fits the
  // odometry's heading. Without a choice (one exit), there is nothing to decide.
  EdgeId best = edge_;
  double best_deg = 1e9;
  for (EdgeId e : exits_) {
    const double d = std::abs(wrap180(road_bearing_deg(e, std::min(past_junction_m_, graph_.length_m(e))) - heading_deg_));
    if (d < best_deg) best = e, best_deg = d;
  }
  edge_ = best;
}

MatchedPoint OdometryMapMatcher::advance(const OdometryStep& step) {
  if (!edge_.valid()) return {};
  const double dist = std::max(0.0, step.distance_m);
  heading_deg_ = wrap180(heading_deg_ + step.heading_change_deg);
  sigma_m_ += config_.drift_per_m * dist;
  headings_.emplace_back(step.time_s, heading_deg_);
  while (!headings_.empty() && headings_.front().first < step.time_s - config_.heading_window_s) headings_.pop_front();

  double left = dist;
  while (left > 0.0) {
    if (!exits_.empty()) {
      // Still deciding the last junction's exit.
      const double take = std::min(left, config_.decision_m - past_junction_m_);
      past_junction_m_ += take;
      offset_m_ += take;
      left -= take;
      decide_exit();
      if (past_junction_m_ >= config_.decision_m) {
        const double turn = wrap180(heading_deg_ - heading_at_junction_deg_);
        exits_.clear();
        // The heading check compares the road with the headings driven on it, not before the turn.
        headings_.clear();
        headings_.emplace_back(step.time_s, heading_deg_);
        if (std::abs(turn) > config_.reset_turn_deg && edge_ != came_from_) {
          // A sharp turn happened at a known junction: the along-road drift is gone (§IV's reset).
          sigma_m_ = config_.base_sigma_m;
          ++resets_;
        }
      }
      if (offset_m_ > graph_.length_m(edge_)) {
        left += offset_m_ - graph_.length_m(edge_);
        offset_m_ = graph_.length_m(edge_);
        exits_.clear();
      } else {
        continue;
      }
    }
    const double to_end = graph_.length_m(edge_) - offset_m_;
    if (left < to_end) {
      offset_m_ += left;
      left = 0.0;
      break;
    }
    left -= to_end;
    // At the junction: every exit but straight back, unless it is a dead end.
    const NodeId junction = graph_.head(edge_);
    came_from_ = edge_;
    exits_.clear();
    for (EdgeId e : graph_.out_edges(junction)) {
      if (e != graph_.twin(edge_)) exits_.push_back(e);
    }
    if (exits_.empty()) {
      for (EdgeId e : graph_.out_edges(junction)) exits_.push_back(e);
    }
    if (exits_.empty()) {  // a sink: stay at its end
      offset_m_ = graph_.length_m(edge_);
      break;
    }
    heading_at_junction_deg_ = headings_.empty() ? heading_deg_ : headings_.front().second;
    past_junction_m_ = 0.0;
    offset_m_ = 0.0;
    edge_ = exits_.front();
    decide_exit();
  }
  // The heading check (§IV): the road and the odometry disagree over the window.
  if (exits_.empty() && step.time_s - last_raise_s_ >= 1.0) {
    double mean = 0.0;
    for (const auto& [t, h] : headings_) mean += std::abs(wrap180(road_bearing_deg(edge_, offset_m_) - h));
    mean /= static_cast<double>(std::max<std::size_t>(1, headings_.size()));
    if (mean > config_.disagreement_deg) {
      sigma_m_ *= config_.disagreement_raise;
      last_raise_s_ = step.time_s;
    }
  }
  last_time_s_ = step.time_s;
  return current();
}

}  // namespace corridor::localizer
