#include "planner/route_steps.hpp"

#include <algorithm>
#include <cmath>

#include "maps/turn_graph.hpp"

namespace corridor::planner {
namespace {

double turn_between(const maps::RoadGraph& g, EdgeId in, EdgeId out) {
  return maps::signed_turn_deg(maps::arriving_bearing_deg(g.geometry(in)), maps::leaving_bearing_deg(g.geometry(out)));
}

// The exits a vehicle passes from entering a roundabout by edges[first] until it leaves after
// edges[last]: the roads leaving the ring at each node it reaches, the one it takes included.
int roundabout_exit(const maps::RoadGraph& g, const std::vector<EdgeId>& edges, std::size_t first, std::size_t last) {
  int exits = 0;
  for (std::size_t k = first; k <= last; ++k) {
    for (EdgeId f : g.out_edges(g.head(edges[k]))) exits += g.on_roundabout(f) ? 0 : 1;
  }
  return std::max(exits, 1);
}

// Folds a first step shorter than min_m into the second (which becomes the depart, from the trip's
// start), and a last one into the one before it. A roundabout step (its exit count) and a U-turn
// are never folded away: they are the instruction. At least one step always stays.
void trim_end_steps(std::vector<RouteStep>& steps, double min_m) {
  auto keeps_instruction = [](const RouteStep& s) {
    return s.maneuver == ManeuverType::roundabout || s.modifier == TurnModifier::uturn;
  };
  while (steps.size() >= 2 && steps.front().distance_m < min_m && !keeps_instruction(steps[1])) {
    RouteStep& next = steps[1];
    next.distance_m += steps.front().distance_m;
    next.duration_s += steps.front().duration_s;
    next.location = steps.front().location;
    next.maneuver = ManeuverType::depart;
    next.modifier = TurnModifier::none;
    next.turn_deg = 0;
    steps.erase(steps.begin());
  }
  while (steps.size() >= 2 && steps.back().distance_m < min_m && !keeps_instruction(steps.back())) {
    RouteStep& previous = steps[steps.size() - 2];
    previous.distance_m += steps.back().distance_m;
    previous.duration_s += steps.back().duration_s;
    steps.pop_back();
  }
}

}  // namespace

const char* to_string(ManeuverType t) {
  switch (t) {
    case ManeuverType::depart: return "depart";
    case ManeuverType::turn: return "turn";
    case ManeuverType::new_name: return "new name";
    case ManeuverType::continue_on: return "continue";
    case ManeuverType::roundabout: return "roundabout";
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
  depart.ferry = g.is_ferry(route.edges[0]);
  depart.location = g.point_along(route.edges[0], route.start.offset_m);
  steps.push_back(depart);
  for (std::size_t i = 0; i < n; ++i) {
    if (i > 0) {
      const EdgeId in = route.edges[i - 1], out = route.edges[i];
      const bool entering = g.on_roundabout(out) && !g.on_roundabout(in);
      const bool inside_or_leaving = g.on_roundabout(in);
      const bool boards_or_leaves = g.is_ferry(in) != g.is_ferry(out);
      if (entering) {
        // One step for the whole roundabout, named after the road it leaves by.
        std::size_t last = i;
        while (last + 1 < n && g.on_roundabout(route.edges[last + 1])) ++last;
        const EdgeId exit_road = last + 1 < n ? route.edges[last + 1] : route.edges[last];
        RouteStep s;
        s.name = g.name(exit_road);
        s.ref = g.ref(exit_road);
        s.maneuver = ManeuverType::roundabout;
        s.exit = last + 1 < n ? roundabout_exit(g, route.edges, i, last) : 0;
        s.turn_deg = turn_between(g, in, exit_road);
        s.modifier = modifier_for_turn(s.turn_deg);
        s.location = g.position(g.tail(out));
        steps.push_back(s);
      } else if (!inside_or_leaving || boards_or_leaves) {
        // (Straight off a roundabout onto a ferry: boarding is a step of its own.)
        const double turn = turn_between(g, in, out);
        const bool renamed = g.name(in) != g.name(out) || g.ref(in) != g.ref(out);
        // A bend at a gate inside one way is no maneuver: the gate is a node only for its delay.
        const bool sharp = std::abs(turn) >= options.continue_turn_deg && !g.continues_way_at_stop(in, out);
        if (renamed || sharp || boards_or_leaves) {
          RouteStep s;
          s.name = g.name(out);
          s.ref = g.ref(out);
          s.turn_deg = turn;
          s.modifier = modifier_for_turn(turn);
          s.maneuver = !renamed ? ManeuverType::continue_on
                       : s.modifier == TurnModifier::straight ? ManeuverType::new_name
                                                               : ManeuverType::turn;
          s.location = g.position(g.tail(out));
          s.ferry = g.is_ferry(out);
          steps.push_back(s);
        }
      }
    }
    steps.back().distance_m += piece_m(i);
    steps.back().duration_s += piece_s(i);
  }
  trim_end_steps(steps, options.min_end_step_m);
  RouteStep arrive;
  arrive.name = steps.back().name;
  arrive.ref = steps.back().ref;
  arrive.maneuver = ManeuverType::arrive;
  arrive.ferry = steps.back().ferry;
  arrive.location = g.point_along(route.edges.back(), route.goal.offset_m);
  steps.push_back(arrive);
  return steps;
}

}  // namespace corridor::planner
