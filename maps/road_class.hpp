// The road classes an emergency vehicle may use, as in OSM's highway=* values, and the ferries
// (route=ferry|shuttle_train) that carry vehicles across water or through a tunnel.
#pragma once

#include <cstdint>
#include <optional>
#include <string_view>

namespace corridor::maps {

enum class RoadClass : std::uint8_t {
  motorway,
  motorway_link,
  trunk,
  trunk_link,
  primary,
  primary_link,
  secondary,
  secondary_link,
  tertiary,
  tertiary_link,
  unclassified,
  residential,
  living_street,
  service,
  emergency_access,  // any other highway=* explicitly open to emergency vehicles
  synthetic,         // generated graphs
  ferry,             // route=ferry or route=shuttle_train: the vehicle rides, at the crossing's pace
};

inline constexpr int kRoadClassCount = 17;

// The class for a highway=* value, or nullopt when that value is not a drivable class.
std::optional<RoadClass> road_class_from_highway(std::string_view highway);
std::string_view to_string(RoadClass c);

}  // namespace corridor::maps
