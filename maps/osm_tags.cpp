#include "maps/osm_tags.hpp"

#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <utility>

namespace corridor::maps {
namespace {

std::string_view trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return s;
}

std::string lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

bool is_one_of(std::string_view v, std::initializer_list<std::string_view> options) {
  for (auto o : options) {
    if (v == o) return true;
  }
  return false;
}

constexpr double kMphToKmh = 1.609344;
constexpr double kKnotToKmh = 1.852;
constexpr double kNoLimitKmh = 140.0;  // "none": cap used where the law sets no limit
constexpr double kWalkKmh = 6.0;

// Implicit limits by country and zone. Generic values cover countries not listed.
struct ImplicitLimit {
  std::string_view country;  // empty = any country
  std::string_view zone;
  double kmh;
};
constexpr std::array<ImplicitLimit, 27> kImplicitLimits{{
    {"gb", "nsl_single", 60 * kMphToKmh},
    {"gb", "nsl_dual", 70 * kMphToKmh},
    {"gb", "motorway", 70 * kMphToKmh},
    {"uk", "nsl_single", 60 * kMphToKmh},
    {"uk", "nsl_dual", 70 * kMphToKmh},
    {"uk", "motorway", 70 * kMphToKmh},
    {"ru", "urban", 60},
    {"ru", "rural", 90},
    {"ru", "motorway", 110},
    {"de", "rural", 100},
    {"de", "motorway", 130},  // advisory speed where there is no limit
    {"at", "rural", 100},
    {"fr", "rural", 80},
    {"ch", "rural", 80},
    {"ch", "motorway", 120},
    {"ch", "trunk", 100},
    {"it", "rural", 90},
    {"it", "trunk", 110},
    {"us", "urban", 25 * kMphToKmh},
    {"", "urban", 50},
    {"", "rural", 90},
    {"", "motorway", 130},
    {"", "trunk", 100},
    {"", "living_street", 7},
    {"", "bicycle_road", 30},
    {"", "walk", kWalkKmh},
    {"", "school", 30},
}};

std::optional<double> parse_number_with_unit(std::string_view s) {
  double value = 0.0;
  const char* begin = s.data();
  const char* end = s.data() + s.size();
  auto [ptr, ec] = std::from_chars(begin, end, value);
  if (ec != std::errc{} || !(value > 0.0) || value > 500.0) return std::nullopt;
  const std::string unit = lower(trim(std::string_view(ptr, static_cast<std::size_t>(end - ptr))));
  if (unit.empty() || unit == "km/h" || unit == "kmh" || unit == "kph") return value;
  if (unit == "mph") return value * kMphToKmh;
  if (unit == "knots") return value * kKnotToKmh;
  return std::nullopt;
}

std::optional<double> parse_implicit(std::string_view country, std::string_view zone) {
  // DE:zone30, DE:zone:30, FR:zone30 and the like carry their number.
  for (std::string_view prefix : {"zone:", "zone"}) {
    if (zone.starts_with(prefix)) {
      if (auto v = parse_number_with_unit(zone.substr(prefix.size()))) return v;
    }
  }
  for (const auto& limit : kImplicitLimits) {
    if (limit.country == country && limit.zone == zone) return limit.kmh;
  }
  for (const auto& limit : kImplicitLimits) {
    if (limit.country.empty() && limit.zone == zone) return limit.kmh;
  }
  return std::nullopt;
}

enum class OnewayRule { both, forward, backward, unusable, unspecified };

OnewayRule parse_oneway(std::string_view v) {
  if (v.empty()) return OnewayRule::unspecified;
  if (is_one_of(v, {"yes", "true", "1"})) return OnewayRule::forward;
  if (is_one_of(v, {"-1", "reverse"})) return OnewayRule::backward;
  if (is_one_of(v, {"no", "false", "0", "alternating"})) return OnewayRule::both;
  if (v == "reversible") return OnewayRule::unusable;
  return OnewayRule::unspecified;
}

// A length in metres: "3.5", "3.5 m", "12'6\"" (feet and inches). nullopt for "default", "none",
// "below_default" and anything else that carries no number.
}  // namespace

std::optional<double> parse_length_m(std::string_view raw) {
  const std::string v = lower(trim(raw));
  if (v.empty()) return std::nullopt;
  if (const auto foot = v.find('\''); foot != std::string::npos) {
    double feet = 0, inches = 0;
    if (std::sscanf(v.c_str(), "%lf'%lf", &feet, &inches) >= 1 && std::isfinite(feet)) {
      return (feet * 12.0 + (std::isfinite(inches) ? inches : 0.0)) * 0.0254;
    }
    return std::nullopt;
  }
  char* end = nullptr;
  const double m = std::strtod(v.c_str(), &end);
  if (end == v.c_str() || !std::isfinite(m) || m <= 0) return std::nullopt;
  const std::string unit = lower(trim(std::string_view(end)));
  if (unit.empty() || unit == "m") return m;
  if (unit == "ft") return m * 0.3048;
  return std::nullopt;
}

namespace {

bool access_item_forbids(std::string_view v) {
  return is_one_of(v, {"no", "agricultural", "forestry", "emergency_no", "use_sidepath", "discouraged", "foot",
                       "bicycle", "horse", "restricted", "military"});
}

// Calls f on each non-empty, trimmed item of a ';'-separated value until f returns false.
template <class F>
void for_each_item(std::string_view v, F&& f) {
  while (!v.empty()) {
    const auto semi = v.find(';');
    const std::string_view item = trim(v.substr(0, semi));
    if (!item.empty() && !f(item)) return;
    if (semi == std::string_view::npos) return;
    v.remove_prefix(semi + 1);
  }
}

// A value or a ';'-separated list of them: forbids when every listed item does.
bool access_forbids(std::string_view v) {
  bool any = false, all = true;
  for_each_item(v, [&](std::string_view item) {
    any = true;
    all = access_item_forbids(item);
    return all;
  });
  return any && all;
}

// The most specific access tag present decides: true when it forbids.
bool most_specific_forbids(std::initializer_list<std::string_view> most_specific_first) {
  for (std::string_view v : most_specific_first) {
    if (!v.empty()) return access_forbids(v);
  }
  return false;
}

}  // namespace

std::uint8_t except_classes(std::string_view list) {
  std::uint8_t mask = 0;
  for_each_item(list, [&](std::string_view item) {
    VehicleClass c{};
    if (vehicle_class_from_name(item, c)) mask |= class_bit(c);
    return true;
  });
  return mask;
}

std::optional<double> parse_weight_t(std::string_view raw) {
  const std::string v = lower(trim(raw));
  if (v.empty()) return std::nullopt;
  char* end = nullptr;
  const double w = std::strtod(v.c_str(), &end);
  if (end == v.c_str() || !std::isfinite(w) || w <= 0) return std::nullopt;
  const std::string unit = lower(trim(std::string_view(end)));
  if (unit.empty() || unit == "t") return w;
  if (unit == "kg") return w / 1000.0;
  if (unit == "st") return w * 0.90718474;
  if (unit == "lbs" || unit == "lb") return w * 0.45359237e-3;
  return std::nullopt;
}

bool node_blocks_emergency(const NodeTags& t) {
  if (is_one_of(t.emergency, {"yes", "designated", "official", "permissive"})) return false;
  if (t.emergency == "no") return true;
  if (most_specific_forbids({t.motorcar, t.motor_vehicle, t.vehicle, t.access})) return true;
  if (t.barrier.empty()) return false;
  if (t.barrier == "bollard") return !is_one_of(t.bollard, {"rising", "removable", "retractable", "foldable", "flexible"});
  if (t.barrier == "kerb") return !is_one_of(t.kerb, {"lowered", "flush", "no"});
  if (t.barrier == "height_restrictor") {
    return false;
  }
  // As OSRM's car profile: these let a car through; every other barrier stops it.
  return !is_one_of(t.barrier, {"no", "gate", "lift_gate", "swing_gate", "sliding_gate", "toll_booth",
                                "border_control", "cattle_grid", "entrance", "sally_port", "arch", "bump_gate"});
}

bool node_stops_vehicle(const NodeTags& t) {
  if (t.barrier.empty() || node_blocks_emergency(t)) return false;
  // Driven over or through at speed.
  if (is_one_of(t.barrier, {"no", "cattle_grid", "entrance", "arch", "height_restrictor", "kerb"})) return false;
  if (t.barrier == "bollard" && t.bollard == "flexible") return false;
  // A gate open to everyone stands open (Valhalla, too, charges a gate only where its access is
  // unknown or private).
  if (t.barrier.find("gate") != std::string_view::npos && is_one_of(t.access, {"yes", "permissive"})) return false;
  return true;
}

std::optional<double> parse_maxspeed_kmh(std::string_view raw) {
  std::string_view v = trim(raw);
  if (const auto semi = v.find(';'); semi != std::string_view::npos) v = trim(v.substr(0, semi));
  if (v.empty()) return std::nullopt;
  const std::string lv = lower(v);
  if (lv == "none") return kNoLimitKmh;
  if (lv == "walk") return kWalkKmh;
  if (auto number = parse_number_with_unit(lv)) return number;
  if (const auto colon = lv.find(':'); colon != std::string::npos && colon > 0) {
    return parse_implicit(std::string_view(lv).substr(0, colon), std::string_view(lv).substr(colon + 1));
  }
  return std::nullopt;
}

double default_speed_kmh(RoadClass c) {
  switch (c) {
    case RoadClass::motorway: return 110;
    case RoadClass::motorway_link: return 60;
    case RoadClass::trunk: return 90;
    case RoadClass::trunk_link: return 50;
    case RoadClass::primary: return 65;
    case RoadClass::primary_link: return 45;
    case RoadClass::secondary: return 55;
    case RoadClass::secondary_link: return 40;
    case RoadClass::tertiary: return 45;
    case RoadClass::tertiary_link: return 35;
    case RoadClass::unclassified: return 40;
    case RoadClass::residential: return 30;
    case RoadClass::living_street: return 10;
    case RoadClass::service: return 20;
    case RoadClass::emergency_access: return 20;
    case RoadClass::synthetic: return 50;
    case RoadClass::ferry: return 5;
  }
  return 30;
}

std::optional<double> parse_duration_s(std::string_view raw) {
  const std::string v = lower(trim(raw));
  if (v.empty()) return std::nullopt;
  double total = 0.0;
  if (v.front() == 'p') {
    // ISO 8601: P[nD][T[nH][nM][nS]].
    bool in_time = false;
    std::size_t i = 1;
    bool any = false;
    while (i < v.size()) {
      if (v[i] == 't') {
        in_time = true;
        ++i;
        continue;
      }
      double n = 0.0;
      const auto [ptr, ec] = std::from_chars(v.data() + i, v.data() + v.size(), n, std::chars_format::fixed);
      if (ec != std::errc{} || ptr == v.data() + v.size() || !std::isfinite(n) || n < 0) return std::nullopt;
      const char unit = *ptr;
      i = static_cast<std::size_t>(ptr - v.data()) + 1;
      if (unit == 'd' && !in_time) total += n * 86400.0;
      else if (unit == 'h' && in_time) total += n * 3600.0;
      else if (unit == 'm' && in_time) total += n * 60.0;
      else if (unit == 's' && in_time) total += n;
      else return std::nullopt;
      any = true;
    }
    if (!any) return std::nullopt;
  } else {
    // hh:mm[:ss], or plain minutes.
    double parts[3] = {0, 0, 0};
    int count = 0;
    std::string_view rest(v);
    while (true) {
      if (count == 3) return std::nullopt;
      double n = 0.0;
      const auto [ptr, ec] = std::from_chars(rest.data(), rest.data() + rest.size(), n, std::chars_format::fixed);
      if (ec != std::errc{} || !std::isfinite(n) || n < 0) return std::nullopt;
      parts[count++] = n;
      rest.remove_prefix(static_cast<std::size_t>(ptr - rest.data()));
      if (rest.empty()) break;
      if (rest.front() != ':') return std::nullopt;
      rest.remove_prefix(1);
    }
    total = count == 1 ? parts[0] * 60.0 : parts[0] * 3600.0 + parts[1] * 60.0 + parts[2];
  }
  constexpr double kYearS = 365.0 * 86400.0;
  if (!(total > 0.0) || !(total <= kYearS)) return std::nullopt;
  return total;
}

std::optional<WayRules> interpret_way(const WayTags& t) {
  const bool ferry = t.route == "ferry" || t.route == "shuttle_train";
  if ((t.highway.empty() && !ferry) || t.area == "yes") return std::nullopt;
  const bool emergency_allowed = is_one_of(t.emergency, {"yes", "designated", "official", "permissive"});
  if (t.emergency == "no") return std::nullopt;

  WayRules rules;
  if (ferry) {
    rules.road_class = RoadClass::ferry;
  } else if (auto cls = road_class_from_highway(t.highway)) {
    rules.road_class = *cls;
  } else if (emergency_allowed) {
    rules.road_class = RoadClass::emergency_access;
  } else {
    return std::nullopt;
  }

  if (!emergency_allowed) {
    if (most_specific_forbids({t.motorcar, t.motor_vehicle, t.vehicle, t.access})) return std::nullopt;
  }
  if (!t.construction.empty() && !is_one_of(t.construction, {"no", "minor"})) return std::nullopt;

  // The most specific oneway tag present decides (oneway:emergency is handled below).
  std::string_view oneway_tag = t.oneway;
  for (std::string_view v : {t.oneway_motorcar, t.oneway_motor_vehicle, t.oneway_vehicle}) {
    if (!v.empty()) {
      oneway_tag = v;
      break;
    }
  }
  OnewayRule oneway = parse_oneway(oneway_tag);
  if (oneway == OnewayRule::unspecified) {
    const bool implied = !ferry && (t.junction == "roundabout" || t.junction == "circular" ||
                                    rules.road_class == RoadClass::motorway);
    oneway = implied ? OnewayRule::forward : OnewayRule::both;
  }
  if (oneway == OnewayRule::unusable) return std::nullopt;
  if (t.oneway_emergency == "no") oneway = OnewayRule::both;
  rules.forward = oneway != OnewayRule::backward;
  rules.backward = oneway != OnewayRule::forward;
  if (!emergency_allowed) {
    if (most_specific_forbids({t.motorcar_forward, t.motor_vehicle_forward, t.vehicle_forward, t.access_forward})) {
      rules.forward = false;
    }
    if (most_specific_forbids(
            {t.motorcar_backward, t.motor_vehicle_backward, t.vehicle_backward, t.access_backward})) {
      rules.backward = false;
    }
  }
  if (!rules.forward && !rules.backward) return std::nullopt;

  if (ferry) {
    // A boat's or a train's pace, not a speed limit: maxspeed does not apply.
    constexpr double kShuttleTrainKmh = 10.0;
    rules.forward_speed_kmh = rules.backward_speed_kmh =
        t.route == "shuttle_train" ? kShuttleTrainKmh : default_speed_kmh(RoadClass::ferry);
    rules.duration_s = parse_duration_s(t.duration).value_or(0.0);
  } else {
    const double fallback = parse_maxspeed_kmh(t.maxspeed).value_or(default_speed_kmh(rules.road_class));
    rules.forward_speed_kmh = parse_maxspeed_kmh(t.maxspeed_forward).value_or(fallback);
    rules.backward_speed_kmh = parse_maxspeed_kmh(t.maxspeed_backward).value_or(fallback);
  }
  rules.max_height_m = parse_length_m(t.maxheight).value_or(0.0);
  rules.max_width_m = parse_length_m(t.maxwidth).value_or(0.0);
  rules.max_weight_t = parse_weight_t(t.maxweight).value_or(0.0);
  rules.roundabout = t.junction == "roundabout" || t.junction == "circular";
  return rules;
}

}  // namespace corridor::maps
