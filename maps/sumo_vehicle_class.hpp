// SUMO's vehicle classes and lane permissions (`allow` / `disallow`), as SUMO reads them: a lane
// with neither is open to every class, `allow` names the only classes it admits, `disallow` the
// ones it refuses. A route SUMO accepts for a vehicle is one whose every edge has a lane its class
// may use, joined by connections whose lanes admit it too.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace corridor::maps {

// One bit per SUMO vehicle class (SUMO 1.15's list, in its order).
using SumoClasses = std::uint32_t;
inline constexpr SumoClasses kAllSumoClasses = ~SumoClasses{0};

// The bit of a class name ("emergency", "bus", ...), or nullopt for a name SUMO 1.15 does not have.
[[nodiscard]] std::optional<SumoClasses> sumo_class_bit(std::string_view name);

// The classes a lane admits. Class names SUMO 1.15 does not know (written by a newer netconvert)
// are skipped: no vehicle of this SUMO can have them. "all" stands for every class.
[[nodiscard]] SumoClasses parse_sumo_permissions(std::string_view allow, std::string_view disallow);

// The space-separated names of the classes in `classes`, for messages.
[[nodiscard]] std::string sumo_class_names(SumoClasses classes);

}  // namespace corridor::maps
