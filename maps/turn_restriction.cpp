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

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

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

std::uint8_t except_classes(std::string_view list) {
  std::uint8_t mask = 0;
  while (!list.empty()) {
    const auto semi = list.find(';');
    VehicleClass c{};
    if (vehicle_class_from_name(trim(list.substr(0, semi)), c)) mask |= class_bit(c);
    if (semi == std::string_view::npos) break;
    list.remove_prefix(semi + 1);
  }
  return mask;
}

}  // namespace corridor::maps
