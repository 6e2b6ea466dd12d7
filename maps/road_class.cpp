#include "maps/road_class.hpp"

#include <array>
#include <utility>

namespace corridor::maps {
namespace {
constexpr std::array<std::pair<std::string_view, RoadClass>, 14> kHighwayClasses{{
    {"motorway", RoadClass::motorway},
    {"motorway_link", RoadClass::motorway_link},
    {"trunk", RoadClass::trunk},
    {"trunk_link", RoadClass::trunk_link},
    {"primary", RoadClass::primary},
    {"primary_link", RoadClass::primary_link},
    {"secondary", RoadClass::secondary},
    {"secondary_link", RoadClass::secondary_link},
    {"tertiary", RoadClass::tertiary},
    {"tertiary_link", RoadClass::tertiary_link},
    {"unclassified", RoadClass::unclassified},
    {"residential", RoadClass::residential},
    {"living_street", RoadClass::living_street},
    {"service", RoadClass::service},
}};
}  // namespace

std::optional<RoadClass> road_class_from_highway(std::string_view highway) {
  for (const auto& [name, cls] : kHighwayClasses) {
    if (name == highway) return cls;
  }
  return std::nullopt;
}

std::string_view to_string(RoadClass c) {
  for (const auto& [name, cls] : kHighwayClasses) {
    if (cls == c) return name;
  }
  switch (c) {
    case RoadClass::emergency_access: return "emergency_access";
    case RoadClass::ferry: return "ferry";
    default: return "synthetic";
  }
}

}  // namespace corridor::maps
