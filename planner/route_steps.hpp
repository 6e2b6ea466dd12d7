// Turn-by-turn steps of a route, as OSRM's `steps` give them: one step per stretch of one street,
// with its distance, duration and the maneuver that starts it.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "planner/route.hpp"

namespace corridor::planner {

enum class ManeuverType { depart, turn, new_name, continue_on, roundabout, arrive };
enum class TurnModifier { none, uturn, sharp_right, right, slight_right, straight, slight_left, left, sharp_left };

// OSRM's words: "depart", "turn", "new name", "continue", "roundabout", "arrive"
const char* to_string(ManeuverType t);
const char* to_string(TurnModifier m);    // "uturn", "sharp right", ..., or "" for none

struct RouteStep {
  std::string name;  // the street driven during the step ("" when unnamed)
  std::string ref;
  double distance_m = 0;
  double duration_s = 0;
  ManeuverType maneuver = ManeuverType::depart;
  TurnModifier modifier = TurnModifier::none;
  maps::Point2 location;  // where the maneuver happens
  double turn_deg = 0;    // signed turn angle at the maneuver, right positive
  int exit = 0;           // for a roundabout: take the exit-th exit (1 = the first)
  bool ferry = false;     // the step rides a ferry or shuttle train (OSRM's mode "ferry")
};

struct StepOptions {
  // A turn at least this sharp starts a new step even when the street's name does not change.
  double continue_turn_deg = 45.0;
  // A first or last step shorter than this is folded into its neighbour: a trip that starts (or
  // ends) within it of a junction starts (or ends) at the junction, and "drive 0.3 m on West Street,
  // then turn left" is noise from the click or the fix, not an instruction. Smaller than any snap
  // or GPS error, so it never hides a street the vehicle really drives.
  double min_end_step_m = 1.0;
};

// The modifier for a signed turn angle (right positive, degrees in (-180, 180]).
TurnModifier modifier_for_turn(double turn_deg);

// Depart, one step per street (or per sharp turn on one street, or per boarding or leaving a
// ferry), arrive. A roundabout is one step, "roundabout" with the exit to take, named after the road
// it leaves by, as OSRM gives it. A first or last step shorter than min_end_step_m is folded into its
// neighbour. Empty for a route not found.
std::vector<RouteStep> route_steps(const maps::RoadGraph& graph, const Route& route, const StepOptions& options = {});

}  // namespace corridor::planner
