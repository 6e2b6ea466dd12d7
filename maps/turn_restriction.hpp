// OSM turn restrictions resolved onto the road graph's edges, in the profile-independent form the
// graph and its cache keep: the edges of the forbidden (or only allowed) manoeuvre, which tag said
// so, and which vehicle classes its `except` names. A vehicle profile decides what binds it.
#pragma once

#include <cstdint>
#include <string_view>
#include <vector>

#include "maps/ids.hpp"

namespace corridor::maps {

// The key a restriction was tagged with: `restriction` binds every vehicle, `restriction:<mode>`
// only that mode. Bits of a mask, so a profile can list the modes it belongs to.
enum class RestrictionMode : std::uint8_t {
  all = 0,            // restriction=*
  motorcar = 1,       // restriction:motorcar=*
  motor_vehicle = 2,  // restriction:motor_vehicle=*
  vehicle = 3,        // restriction:vehicle=*
  emergency = 4,      // restriction:emergency=*
  hgv = 5,            // restriction:hgv=* (binds a heavy fire engine, not an ambulance)
};
inline constexpr std::uint8_t mode_bit(RestrictionMode m) { return static_cast<std::uint8_t>(1u << static_cast<unsigned>(m)); }

// The vehicle classes an `except=*` list may name, as bits of a mask. A profile lists the classes
// its vehicle belongs to (an ambulance is a motorcar and an emergency vehicle; a fire engine an hgv
// and an emergency vehicle), and an `except` naming any of them lifts the restriction for it.
enum class VehicleClass : std::uint8_t {
  motorcar = 0,
  motor_vehicle = 1,
  vehicle = 2,
  emergency = 3,
  hgv = 4,
  psv = 5,
};
inline constexpr int kVehicleClassCount = 6;
inline constexpr std::uint8_t class_bit(VehicleClass c) { return static_cast<std::uint8_t>(1u << static_cast<unsigned>(c)); }

// The class a name stands for ("motorcar"), or false when it is not one.
bool vehicle_class_from_name(std::string_view name, VehicleClass& out);
std::string_view to_string(VehicleClass c);

// Flat arrays (the cache stores them as they are). Restriction r forbids driving
// edges[first[r] .. first[r+1]) in that order (from, via edges..., to): a via-node restriction has
// two edges, a via-way one more. An `only_*` restriction instead forbids every other way out of the
// from edge and, along its via edges, every way off them.
struct TurnRestrictions {
  std::vector<std::uint32_t> first{0};
  std::vector<EdgeId> edges;
  std::vector<std::uint8_t> only;             // 1 for only_*
  std::vector<std::uint8_t> mode;             // RestrictionMode
  std::vector<std::uint8_t> except;  // VehicleClass bits its `except` names (0: none)

  [[nodiscard]] std::size_t size() const { return only.size(); }
  void add(const std::vector<EdgeId>& path, bool is_only, RestrictionMode m, std::uint8_t except_mask) {
    edges.insert(edges.end(), path.begin(), path.end());
    first.push_back(static_cast<std::uint32_t>(edges.size()));
    only.push_back(is_only ? 1 : 0);
    mode.push_back(static_cast<std::uint8_t>(m));
    except.push_back(except_mask);
  }
};

}  // namespace corridor::maps
