// Interpretation of OSM way tags for emergency vehicles: which ways are drivable, in which
// directions, and at what speed. Pure functions, so that every rule is unit-tested.
#pragma once

#include <optional>
#include <string_view>

#include "maps/road_class.hpp"

namespace corridor::maps {

// The tags the rules read; an absent tag is an empty view.
struct WayTags {
  std::string_view highway;
  std::string_view junction;
  std::string_view oneway;
  std::string_view oneway_emergency;  // oneway:emergency
  std::string_view maxspeed;
  std::string_view maxspeed_forward;
  std::string_view maxspeed_backward;
  std::string_view access;
  std::string_view vehicle;
  std::string_view motor_vehicle;
  std::string_view motorcar;
  std::string_view emergency;
  std::string_view area;
};

struct WayRules {
  RoadClass road_class = RoadClass::residential;
  bool forward = true;   // drivable in the way's node order
  bool backward = true;  // drivable against it
  double forward_speed_kmh = 0.0;
  double backward_speed_kmh = 0.0;
};

// Rules for an emergency vehicle, or nullopt when it may not use the way at all.
//  - Classes motorway..residential, living_street, service and the *_link classes are drivable, and so
//    is any highway=* with emergency=yes|designated.
//  - emergency=no forbids; emergency=yes|designated permits whatever access says. Otherwise the most
//    specific of motorcar, motor_vehicle, vehicle, access decides: no / agricultural / forestry /
//    discouraged-style bans forbid; private, destination, delivery, customers and permissive do not
//    stop an emergency vehicle.
//  - oneway=yes|true|1 / -1|reverse / no; junction=roundabout|circular and highway=motorway imply
//    oneway; oneway=reversible is not usable; oneway:emergency=no lifts the restriction.
std::optional<WayRules> interpret_way(const WayTags& tags);

// A maxspeed value in km/h: plain numbers, "mph" and "knots" units, "none", "walk", and the implicit
// country values ("DE:urban", "FR:rural", "CH:motorway", "GB:nsl_single", "DE:zone30", ...).
// nullopt for values that carry no speed ("signals", "variable") or cannot be parsed.
std::optional<double> parse_maxspeed_kmh(std::string_view value);

// Free-flow speed assumed where maxspeed is missing (documented in README "Speed defaults").
double default_speed_kmh(RoadClass c);

}  // namespace corridor::maps
