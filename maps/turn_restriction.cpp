#include "maps/turn_restriction.hpp"

#include <array>
#include <utility>

namespace corridor::maps {
namespace {

constexpr std::array<std::pair<std::string_view, VehicleClass>, kVehicleClassCount> kClassNames{{
    {"motorcar", VehicleClass::motorcar},
    {"motor_vehicle", VehicleClass::motor_vehicle},
    {"vehicle", VehicleClass::vehicle},
    {"emergency", VehicleClass::emergency},
    {"hgv", VehicleClass::hgv},
    {"psv", VehicleClass::psv},
}};

}  // namespace

bool vehicle_class_from_name(std::string_view name, VehicleClass& out) {
  for (const auto& [n, c] : kClassNames) {
    if (n == name) {
      out = c;
      return true;
    }
  }
  return false;
}

std::string_view to_string(VehicleClass c) { return kClassNames[static_cast<std::size_t>(c)].first; }

}  // namespace corridor::maps
