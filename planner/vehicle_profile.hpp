// What a vehicle is and which rules bind it: its top speed and dimensions, the turn restrictions
// and physical limits it obeys, its turn costs and U-turn policy. A plain struct, loadable from JSON,
// with the two shipped profiles (an ambulance and a fire engine).
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>

#include "maps/road_class.hpp"
#include "maps/turn_restriction.hpp"

namespace corridor::planner {

class ProfileError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

enum class UturnPolicy : std::uint8_t {
  dead_ends,  // only where the road ends (or a barrier closes it): the only way on
  anywhere,   // at any intersection, at uturn_penalty_s
};

struct VehicleProfile {
  double vmax_mps = 120.0 / 3.6;
  std::string name = "ambulance";
  // Dimensions, checked against maxheight / maxwidth / maxweight and height restrictors.
  double height_m = 2.9;
  double width_m = 2.3;
  double weight_t = 4.6;
  // Which `restriction:<mode>` keys bind it (maps::mode_bit), and the vehicle classes it belongs to
  // (maps::class_bit): an `except` naming one of them lifts a restriction for it. An ambulance is a
  // motorcar, a fire engine an hgv; both are emergency vehicles, and `except=psv` lifts a
  // restriction for them too (bus gates and lanes are open to emergency services).
  std::uint8_t restriction_modes = maps::mode_bit(maps::RestrictionMode::all) | maps::mode_bit(maps::RestrictionMode::motorcar) |
                                   maps::mode_bit(maps::RestrictionMode::motor_vehicle) |
                                   maps::mode_bit(maps::RestrictionMode::vehicle) |
                                   maps::mode_bit(maps::RestrictionMode::emergency);
  std::uint8_t except_classes = maps::class_bit(maps::VehicleClass::motorcar) | maps::class_bit(maps::VehicleClass::motor_vehicle) |
                                maps::class_bit(maps::VehicleClass::vehicle) | maps::class_bit(maps::VehicleClass::emergency) |
                                maps::class_bit(maps::VehicleClass::psv);
  // Turn cost: turn_penalty_s × (1 − cos θ) / 2 for a turn of θ (a right angle costs half of it), plus
  // crossing_penalty_s for a turn across oncoming traffic (a left turn where traffic keeps right).
  double turn_penalty_s = 6.0;
  double crossing_penalty_s = 3.0;
  UturnPolicy uturn_policy = UturnPolicy::dead_ends;
  double uturn_penalty_s = 30.0;
  // The time lost at each barrier the vehicle passes but stops at (maps::node_stops_vehicle: a
  // gate, a toll booth, a border post, a bollard to lower): waiting for it to open. 30 s, as
  // Valhalla charges for a gate; a route through one is taken only when it saves more than that.
  double barrier_delay_s = 30.0;
  // Whether it boards ferries and shuttle trains (class ferry). Both shipped profiles do, as OSRM's
  // car does: on an island the ferry is the only way. A service whose boats take no vehicles, or
  // whose crews must never be routed onto one, sets it false.
  bool ferries = true;
  // Multiplies the legal speed per road class (before vmax caps it): an emergency vehicle with
  // lights and siren runs a little above the limit on main roads, slower on narrow residential ones.
  std::array<double, maps::kRoadClassCount> speed_factor = [] {
    std::array<double, maps::kRoadClassCount> f{};
    f.fill(1.0);
    return f;
  }();
};

VehicleProfile ambulance_profile();
VehicleProfile fire_engine_profile();

// By name: "ambulance" or "fire_engine". Throws ProfileError for another name.
VehicleProfile builtin_profile(std::string_view name);

// JSON: every field optional over the ambulance's defaults, or {"base": "fire_engine", ...}.
//   {"name", "base", "vmax_kmh", "height_m", "width_m", "weight_t", "restriction_modes": ["motorcar", ...],
//    "except_classes": ["motorcar", "emergency", ...], "ferries", "turn_penalty_s", "crossing_penalty_s", "uturn": "dead_ends"|"anywhere",
//    "uturn_penalty_s", "barrier_delay_s", "speed_factor": {"residential": 0.9, ...}}
// "emergency_exceptions" (the key before except_classes) is still read: false means no `except`
// lifts a restriction for the vehicle, true adds emergency and psv to its classes.
// Throws ProfileError naming the field for malformed JSON, an unknown key, a wrong type, or a value
// out of range.
VehicleProfile profile_from_json(std::string_view json);
VehicleProfile load_profile(const std::filesystem::path& file);
// A built-in name, else a JSON file. Throws ProfileError when it is neither.
VehicleProfile profile_by_name_or_file(const std::string& name_or_file);
std::string profile_to_json(const VehicleProfile& profile);

// Checks ranges; throws ProfileError.
void validate(const VehicleProfile& profile);

}  // namespace corridor::planner
