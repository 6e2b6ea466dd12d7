#include "maps/sumo_vehicle_class.hpp"

#include <array>

namespace corridor::maps {
namespace {

// SUMO 1.15's SumoVehicleClassStrings, in bit order.
constexpr std::array<std::string_view, 27> kNames{
    "ignoring", "private",    "emergency", "authority",     "army",      "vip",  "pedestrian", "passenger", "hov",
    "taxi",     "bus",        "coach",     "delivery",      "truck",     "trailer", "motorcycle", "moped", "bicycle",
    "evehicle", "tram",       "rail_urban", "rail",         "rail_electric", "rail_fast", "ship", "custom1", "custom2"};

template <class F>
void for_each_word(std::string_view text, F&& f) {
  std::size_t i = 0;
  while (i < text.size()) {
    while (i < text.size() && (text[i] == ' ' || text[i] == '\t' || text[i] == ',')) ++i;
    std::size_t j = i;
    while (j < text.size() && text[j] != ' ' && text[j] != '\t' && text[j] != ',') ++j;
    if (j > i) f(text.substr(i, j - i));
    i = j;
  }
}

SumoClasses classes_of(std::string_view list) {
  SumoClasses out = 0;
  for_each_word(list, [&](std::string_view word) {
    if (word == "all") {
      out = kAllSumoClasses;
    } else if (const auto bit = sumo_class_bit(word)) {
      out |= *bit;
    }
  });
  return out;
}

}  // namespace

std::optional<SumoClasses> sumo_class_bit(std::string_view name) {
  for (std::size_t i = 0; i < kNames.size(); ++i) {
    if (kNames[i] == name) return SumoClasses{1} << i;
  }
  return std::nullopt;
}

SumoClasses parse_sumo_permissions(std::string_view allow, std::string_view disallow) {
  // SUMO reads allow when both are given.
  if (!allow.empty()) return classes_of(allow);
  if (!disallow.empty()) return kAllSumoClasses & ~classes_of(disallow);
  return kAllSumoClasses;
}

std::string sumo_class_names(SumoClasses classes) {
  if (classes == kAllSumoClasses) return "all";
  std::string out;
  for (std::size_t i = 0; i < kNames.size(); ++i) {
    if ((classes & (SumoClasses{1} << i)) != 0) out += (out.empty() ? "" : " ") + std::string(kNames[i]);
  }
  return out.empty() ? "none" : out;
}

}  // namespace corridor::maps
