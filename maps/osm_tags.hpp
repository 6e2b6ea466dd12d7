// Interpretation of OSM way tags for emergency vehicles: which ways are drivable, in which
// directions, and at what speed. Pure functions, so that every rule is unit-tested.
#pragma once

#include <optional>
#include <string_view>

#include "maps/road_class.hpp"
#include "maps/turn_restriction.hpp"

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
  std::string_view construction;
  // Mode-specific oneway (oneway:motorcar, oneway:motor_vehicle, oneway:vehicle).
  std::string_view oneway_motorcar;
  std::string_view oneway_motor_vehicle;
  std::string_view oneway_vehicle;
  // Direction-specific access: *:forward and *:backward of motorcar, motor_vehicle, vehicle, access.
  std::string_view motorcar_forward, motorcar_backward;
  std::string_view motor_vehicle_forward, motor_vehicle_backward;
  std::string_view vehicle_forward, vehicle_backward;
  std::string_view access_forward, access_backward;
  // Physical limits.
  std::string_view maxheight, maxwidth, maxweight;
  // Ferries: route=ferry|shuttle_train, and the crossing's duration ("0:45", "1:30:00", "PT45M").
  std::string_view route;
  std::string_view duration;
};

// The tags of a node that may stop a vehicle on the way through it.
struct NodeTags {
  std::string_view barrier;
  std::string_view bollard;  // bollard=rising|removable|... for barrier=bollard
  std::string_view kerb;     // kerb=lowered|flush|raised|... for barrier=kerb
  std::string_view maxheight;
  std::string_view access;
  std::string_view vehicle;
  std::string_view motor_vehicle;
  std::string_view motorcar;
  std::string_view emergency;
};

struct WayRules {
  RoadClass road_class = RoadClass::residential;
  bool forward = true;   // drivable in the way's node order
  bool backward = true;  // drivable against it
  double forward_speed_kmh = 0.0;
  double backward_speed_kmh = 0.0;
  // Physical limits from maxheight, maxwidth and maxweight; 0 where the way has none. Which vehicle
  // they stop is the vehicle profile's business, not the map's.
  double max_height_m = 0.0;
  double max_width_m = 0.0;
  double max_weight_t = 0.0;
  bool roundabout = false;  // junction=roundabout|circular
  // A ferry's crossing time from its duration tag, for the whole way; 0 when it has none (the
  // importer then keeps the class's speed). The importer spreads it over the way by length.
  double duration_s = 0.0;
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
//  - Access values may be lists ("agricultural;forestry"): a list forbids when every item does.
//    foot, bicycle, horse, restricted and military forbid as no does.
//  - construction=* other than no/minor closes the way.
//  - oneway:emergency, then oneway:motorcar, oneway:motor_vehicle, oneway:vehicle override oneway;
//    *:forward / *:backward access (motorcar, motor_vehicle, vehicle, access, most specific first)
//    closes one direction.
//  - route=ferry|shuttle_train (with or without a highway tag) is class ferry, as OSRM's car
//    profile reads it: the same access rules, no implied oneway, 5 km/h for a ferry and 10 km/h for
//    a shuttle train unless its duration says otherwise. Whether a vehicle boards ferries at all is
//    its profile's choice.
std::optional<WayRules> interpret_way(const WayTags& tags);

// A duration in seconds: "hh:mm", "hh:mm:ss", a number of minutes, or ISO 8601 ("PT1H30M",
// "P1DT2H"). Plain decimals only (no exponents). nullopt for anything else, for zero, and for more
// than a year.
std::optional<double> parse_duration_s(std::string_view value);

// A length in metres: "3.5", "3.5 m", "12 ft", "11'6\"". nullopt for "default", "none",
// "below_default" and anything unparsable (no limit is assumed then).
std::optional<double> parse_length_m(std::string_view value);
// A weight in tonnes: "7.5", "7.5 t", "7500 kg", "10 st" (short tons), "20000 lbs".
std::optional<double> parse_weight_t(std::string_view value);

// True when an emergency vehicle cannot pass through a node, as OSRM's car profile reads barriers:
// gate, lift_gate, swing_gate, sliding_gate, toll_booth, border_control, cattle_grid, entrance,
// sally_port, arch and bump_gate let it through, and every other barrier stops it. Exceptions:
//  - retractable bollards (bollard=rising|removable|retractable|foldable|flexible), which emergency
//    services lower;
//  - a kerb tagged kerb=lowered|flush|no;
//  - a height_restrictor: the importer turns its maxheight into a limit on the roads through it,
//    which the vehicle profile checks (here it stops nothing).
// access=no (or vehicle/motor_vehicle/motorcar=no, as on ways) on a node blocks too, and
// emergency=yes|designated on the node lets the vehicle through any of these.
bool node_blocks_emergency(const NodeTags& tags);

// True for a barrier the vehicle passes but must stop at: a gate the car profile lets through
// (gate, lift_gate, swing_gate, sliding_gate, bump_gate, sally_port) unless access=yes|permissive
// keeps it open, a toll booth, a border post, a bollard someone must lower or remove (rising,
// removable, retractable, foldable), and any barrier that only emergency=yes lets it through
// (a block, a chain, a fixed bollard). Not what it drives over: a cattle grid, an entrance, an
// arch, a kerb, a flexible bollard, a height restrictor. The profile charges a delay for each
// (planner::VehicleProfile::barrier_delay_s), as Valhalla's gate cost does. False for a barrier that
// blocks the vehicle: no route passes it at all.
bool node_stops_vehicle(const NodeTags& tags);

// A maxspeed value in km/h: plain numbers, "mph" and "knots" units, "none", "walk", and the implicit
// country values ("DE:urban", "FR:rural", "CH:motorway", "GB:nsl_single", "DE:zone30", ...).
// nullopt for values that carry no speed ("signals", "variable") or cannot be parsed.
std::optional<double> parse_maxspeed_kmh(std::string_view value);

// The vehicle classes an `except=*` list names ("psv;emergency"), as VehicleClass bits. Values that
// are no VehicleClass (bicycle, bus, ...) name no class a profile can belong to and are ignored.
std::uint8_t except_classes(std::string_view list);

// Free-flow speed assumed where maxspeed is missing (documented in README "Speed defaults").
double default_speed_kmh(RoadClass c);

}  // namespace corridor::maps
