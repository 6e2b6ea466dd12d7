#include "planner/vehicle_profile.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

namespace corridor::planner {
namespace {

using maps::RestrictionMode;

constexpr std::pair<std::string_view, RestrictionMode> kModes[] = {
    {"all", RestrictionMode::all},
    {"motorcar", RestrictionMode::motorcar},
    {"motor_vehicle", RestrictionMode::motor_vehicle},
    {"vehicle", RestrictionMode::vehicle},
    {"emergency", RestrictionMode::emergency},
    {"hgv", RestrictionMode::hgv},
};

// The plain numeric fields, by their JSON key.
constexpr std::pair<const char*, double VehicleProfile::*> kNumbers[] = {
    {"height_m", &VehicleProfile::height_m},
    {"width_m", &VehicleProfile::width_m},
    {"weight_t", &VehicleProfile::weight_t},
    {"turn_penalty_s", &VehicleProfile::turn_penalty_s},
    {"crossing_penalty_s", &VehicleProfile::crossing_penalty_s},
    {"uturn_penalty_s", &VehicleProfile::uturn_penalty_s},
    {"barrier_delay_s", &VehicleProfile::barrier_delay_s},
};

void require(bool ok, const std::string& what) {
  if (!ok) throw ProfileError("vehicle profile: " + what);
}

double number(const nlohmann::json& j, const char* key) {
  require(j.is_number(), std::string("'") + key + "' must be a number");
  const double v = j.get<double>();
  require(std::isfinite(v), std::string("'") + key + "' must be finite");
  return v;
}

}  // namespace

VehicleProfile ambulance_profile() { return VehicleProfile{}; }

VehicleProfile fire_engine_profile() {
  VehicleProfile p;
  p.name = "fire_engine";
  p.vmax_mps = 90.0 / 3.6;
  p.height_m = 3.5;
  p.width_m = 2.55;
  p.weight_t = 15.0;
  p.restriction_modes |= maps::mode_bit(RestrictionMode::hgv);
  // A 15 t truck: `except=motorcar` does not lift a restriction for it, `except=hgv` does.
  p.except_classes = static_cast<std::uint8_t>((p.except_classes & ~maps::class_bit(maps::VehicleClass::motorcar)) |
                                               maps::class_bit(maps::VehicleClass::hgv));
  // A 10 m rigid truck slows down more for a turn, and waits longer for a gap to cross.
  p.turn_penalty_s = 9.0;
  p.crossing_penalty_s = 4.0;
  p.speed_factor[static_cast<std::size_t>(maps::RoadClass::living_street)] = 0.8;
  p.speed_factor[static_cast<std::size_t>(maps::RoadClass::service)] = 0.8;
  return p;
}

VehicleProfile builtin_profile(std::string_view name) {
  if (name == "ambulance") return ambulance_profile();
  if (name == "fire_engine") return fire_engine_profile();
  throw ProfileError("unknown vehicle profile '" + std::string(name) + "' (known: ambulance, fire_engine)");
}

void validate(const VehicleProfile& p) {
  require(std::isfinite(p.vmax_mps) && p.vmax_mps > 0 && p.vmax_mps <= 400 / 3.6, "vmax must be in (0, 400] km/h");
  require(std::isfinite(p.height_m) && p.height_m > 0 && p.height_m <= 6, "height_m must be in (0, 6]");
  require(std::isfinite(p.width_m) && p.width_m > 0 && p.width_m <= 4, "width_m must be in (0, 4]");
  require(std::isfinite(p.weight_t) && p.weight_t > 0 && p.weight_t <= 100, "weight_t must be in (0, 100]");
  require(std::isfinite(p.turn_penalty_s) && p.turn_penalty_s >= 0 && p.turn_penalty_s <= 120,
          "turn_penalty_s must be in [0, 120]");
  require(std::isfinite(p.crossing_penalty_s) && p.crossing_penalty_s >= 0 && p.crossing_penalty_s <= 120,
          "crossing_penalty_s must be in [0, 120]");
  require(std::isfinite(p.uturn_penalty_s) && p.uturn_penalty_s >= 0 && p.uturn_penalty_s <= 600,
          "uturn_penalty_s must be in [0, 600]");
  require(std::isfinite(p.barrier_delay_s) && p.barrier_delay_s >= 0 && p.barrier_delay_s <= 3600,
          "barrier_delay_s must be in [0, 3600]");
  // Above 1 an edge could cost less than its free-flow time at the legal speed, which the landmark
  // bound assumes is the least any edge costs.
  for (double f : p.speed_factor) require(std::isfinite(f) && f > 0 && f <= 1, "speed factors must be in (0, 1]");
}

VehicleProfile profile_from_json(std::string_view text) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    // parse_error, and out_of_range for a number too large for a double (found by profile_fuzzer).
    throw ProfileError(std::string("vehicle profile is not valid JSON: ") + e.what());
  }
  require(j.is_object(), "must be a JSON object");
  VehicleProfile p;
  if (const auto base = j.find("base"); base != j.end()) {
    require(base->is_string(), "'base' must be a string");
    p = builtin_profile(base->get<std::string>());
  }
  for (const auto& item : j.items()) {
    const std::string& key = item.key();  // not a structured binding: the lambda below captures it
    const nlohmann::json& value = item.value();
    if (key == "base") continue;
    if (key == "name") {
      require(value.is_string(), "'name' must be a string");
      p.name = value.get<std::string>();
    } else if (key == "vmax_kmh") {
      p.vmax_mps = number(value, "vmax_kmh") / 3.6;
    } else if (const auto field = std::find_if(std::begin(kNumbers), std::end(kNumbers), [&](const auto& f) { return key == f.first; });
               field != std::end(kNumbers)) {
      p.*(field->second) = number(value, field->first);
    } else if (key == "emergency_exceptions") {
      require(value.is_boolean(), "'emergency_exceptions' must be true or false");
      require(!j.contains("except_classes"), "give 'except_classes' or the older 'emergency_exceptions', not both");
      constexpr auto kEmergency = static_cast<std::uint8_t>(maps::class_bit(maps::VehicleClass::emergency) |
                                                            maps::class_bit(maps::VehicleClass::psv));
      p.except_classes = value.get<bool>() ? static_cast<std::uint8_t>(p.except_classes | kEmergency) : std::uint8_t{0};
    } else if (key == "except_classes") {
      require(value.is_array(), "'except_classes' must be an array of vehicle class names");
      p.except_classes = 0;
      for (const auto& c : value) {
        maps::VehicleClass cls{};
        require(c.is_string() && maps::vehicle_class_from_name(c.get<std::string>(), cls),
                "unknown vehicle class " + c.dump() + " in except_classes (known: motorcar, motor_vehicle, vehicle, emergency, hgv, psv)");
        p.except_classes |= maps::class_bit(cls);
      }
    } else if (key == "ferries") {
      require(value.is_boolean(), "'ferries' must be true or false");
      p.ferries = value.get<bool>();
    } else if (key == "uturn") {
      require(value == "dead_ends" || value == "anywhere", "'uturn' must be \"dead_ends\" or \"anywhere\"");
      p.uturn_policy = value == "anywhere" ? UturnPolicy::anywhere : UturnPolicy::dead_ends;
    } else if (key == "restriction_modes") {
      require(value.is_array(), "'restriction_modes' must be an array of mode names");
      p.restriction_modes = 0;
      for (const auto& m : value) {
        bool known = false;
        for (const auto& [mode_name, mode] : kModes) {
          if (m.is_string() && m.get<std::string>() == mode_name) {
            p.restriction_modes |= maps::mode_bit(mode);
            known = true;
          }
        }
        require(known, "unknown restriction mode " + m.dump() + " (known: all, motorcar, motor_vehicle, vehicle, emergency, hgv)");
      }
    } else if (key == "speed_factor") {
      require(value.is_object(), "'speed_factor' must be an object of road class -> factor");
      for (const auto& [cls, f] : value.items()) {
        bool known = false;
        for (int c = 0; c < maps::kRoadClassCount; ++c) {
          if (maps::to_string(static_cast<maps::RoadClass>(c)) == cls) {
            p.speed_factor[static_cast<std::size_t>(c)] = number(f, "speed_factor");
            known = true;
          }
        }
        require(known, "unknown road class '" + cls + "' in speed_factor");
      }
    } else {
      throw ProfileError("vehicle profile: unknown key '" + key + "'");
    }
  }
  validate(p);
  return p;
}

VehicleProfile load_profile(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw ProfileError("cannot read vehicle profile '" + file.string() + "'");
  std::stringstream buffer;
  buffer << in.rdbuf();
  try {
    return profile_from_json(buffer.str());
  } catch (const ProfileError& e) {
    throw ProfileError(file.string() + ": " + e.what());
  }
}

VehicleProfile profile_by_name_or_file(const std::string& name_or_file) {
  if (name_or_file == "ambulance" || name_or_file == "fire_engine") return builtin_profile(name_or_file);
  std::error_code ec;
  if (!std::filesystem::is_regular_file(name_or_file, ec)) {
    throw ProfileError("unknown vehicle profile '" + name_or_file +
                       "': neither a built-in profile (ambulance, fire_engine) nor a profile JSON file");
  }
  return load_profile(name_or_file);
}

std::string profile_to_json(const VehicleProfile& p) {
  nlohmann::json j;
  j["name"] = p.name;
  j["vmax_kmh"] = p.vmax_mps * 3.6;
  for (const auto& [key, field] : kNumbers) j[key] = p.*field;
  j["restriction_modes"] = nlohmann::json::array();
  for (const auto& [name, mode] : kModes) {
    if ((p.restriction_modes & maps::mode_bit(mode)) != 0) j["restriction_modes"].push_back(name);
  }
  j["except_classes"] = nlohmann::json::array();
  for (int c = 0; c < maps::kVehicleClassCount; ++c) {
    const auto cls = static_cast<maps::VehicleClass>(c);
    if ((p.except_classes & maps::class_bit(cls)) != 0) j["except_classes"].push_back(std::string(maps::to_string(cls)));
  }
  j["ferries"] = p.ferries;
  j["uturn"] = p.uturn_policy == UturnPolicy::anywhere ? "anywhere" : "dead_ends";
  for (int c = 0; c < maps::kRoadClassCount; ++c) {
    j["speed_factor"][std::string(maps::to_string(static_cast<maps::RoadClass>(c)))] = p.speed_factor[static_cast<std::size_t>(c)];
  }
  return j.dump(2);
}

}  // namespace corridor::planner
