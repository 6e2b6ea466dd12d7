#include "planner/route_steps.hpp"

#include <cmath>
#include <numbers>

namespace corridor::planner {
namespace {

// Compass bearing (clockwise from north, degrees) of the direction a -> b in the local frame (x east,
// y north).
double bearing_deg(maps::Point2 a, maps::Point2 b) {
  return std::atan2(b.x_m - a.x_m, b.y_m - a.y_m) * 180.0 / std::numbers::pi;
}

// Bearing leaving the edge's tail and arriving at its head, from the first and last pieces of its
// geometry longer than a few centimetres.
double leaving_bearing(const maps::RoadGraph& g, EdgeId e) {
  const auto pts = g.geometry(e);
  for (std::size_t i = 1; i < pts.size(); ++i) {
    if (maps::distance_m(pts[0], pts[i]) > 0.05) return bearing_deg(pts[0], pts[i]);
  }
  return bearing_deg(pts.front(), pts.back());
}
double arriving_bearing(const maps::RoadGraph& g, EdgeId e) {
  const auto pts = g.geometry(e);
  for (std::size_t i = pts.size() - 1; i-- > 0;) {
    if (maps::distance_m(pts[i], pts.back()) > 0.05) return bearing_deg(pts[i], pts.back());
  }
  return bearing_deg(pts.front(), pts.back());
}

double signed_turn_deg(double from_bearing, double to_bearing) {
  double d = std::fmod(to_bearing - from_bearing, 360.0);
  if (d <= -180.0) d += 360.0;
  if (d > 180.0) d -= 360.0;
  return d;
}

}  // namespace

const char* to_string(ManeuverType t) {
  switch (t) {
    case ManeuverType::depart: return "depart";
    case ManeuverType::turn: return "turn";
    case ManeuverType::new_name: return "new name";
    case ManeuverType::continue_on: return "continue";
    case ManeuverType::arrive: return "arrive";
  }
  return "turn";
}

const char* to_string(TurnModifier m) {
  switch (m) {
    case TurnModifier::none: return "";
    case TurnModifier::uturn: return "uturn";
    case TurnModifier::sharp_right: return "sharp right";
    case TurnModifier::right: return "right";
    case TurnModifier::slight_right: return "slight right";
    case TurnModifier::straight: return "straight";
    case TurnModifier::slight_left: return "slight left";
    case TurnModifier::left: return "left";
    case TurnModifier::sharp_left: return "sharp left";
  }
  return "";
}

TurnModifier modifier_for_turn(double turn_deg) {
  const double a = std::abs(turn_deg);
  const bool right = turn_deg > 0.0;
  if (a < 20.0) return TurnModifier::straight;
  if (a < 60.0) return right ? TurnModifier::slight_right : TurnModifier::slight_left;
  if (a < 140.0) return right ? TurnModifier::right : TurnModifier::left;
  if (a < 170.0) return right ? TurnModifier::sharp_right : TurnModifier::sharp_left;
  return TurnModifier::uturn;
}

std::vector<RouteStep> route_steps(const maps::RoadGraph& g, const Route& route, const StepOptions& options) {
  std::vector<RouteStep> steps;
  if (!route.found || route.edges.empty()) return steps;
  const std::size_t n = route.edges.size();
  auto piece_m = [&](std::size_t i) {
    const double from = i == 0 ? route.start.offset_m : 0.0;
    const double to = i + 1 == n ? route.goal.offset_m : g.length_m(route.edges[i]);
    return std::max(0.0, to - from);
  };
  // arrival_s[i] is the arrival at nodes[i] = head(edges[i]); the last edge ends at the goal.
  auto piece_s = [&](std::size_t i) {
    const double begin = i == 0 ? 0.0 : route.arrival_s[i - 1];
    const double end = i + 1 == n ? route.travel_time_s : route.arrival_s[i];
    return std::max(0.0, end - begin);
  };

  RouteStep depart;
  depart.name = g.name(route.edges[0]);
  depart.ref = g.ref(route.edges[0]);
  depart.maneuver = ManeuverType::depart;
  depart.location = g.point_along(route.edges[0], route.start.offset_m);
  steps.push_back(depart);
  for (std::size_t i = 0; i < n; ++i) {
    if (i > 0) {
      const EdgeId in = route.edges[i - 1], out = route.edges[i];
      const double turn = signed_turn_deg(arriving_bearing(g, in), leaving_bearing(g, out));
      const bool renamed = g.name(in) != g.name(out) || g.ref(in) != g.ref(out);
      const bool sharp = std::abs(turn) >= options.continue_turn_deg;
      if (renamed || sharp) {
        RouteStep s;
        s.name = g.name(out);
        s.ref = g.ref(out);
        s.turn_deg = turn;
        s.modifier = modifier_for_turn(turn);
        s.maneuver = !renamed ? ManeuverType::continue_on
                     : s.modifier == TurnModifier::straight ? ManeuverType::new_name
                                                             : ManeuverType::turn;
        s.location = g.position(g.tail(out));
        steps.push_back(s);
      }
    }
    steps.back().distance_m += piece_m(i);
    steps.back().duration_s += piece_s(i);
  }
  RouteStep arrive;
  arrive.name = g.name(route.edges.back());
  arrive.ref = g.ref(route.edges.back());
  arrive.maneuver = ManeuverType::arrive;
  arrive.location = g.point_along(route.edges.back(), route.goal.offset_m);
  steps.push_back(arrive);
  return steps;
}

}  // namespace corridor::planner
