// Ids that reach Corridor from outside (vehicle ids, controller ids, token names): printable
// ASCII, space to '~', 1 to 64 characters, no space at either end. A NUL or a line break in an id
// would cut a log line or a CSV row, or smuggle a header into a reply; a byte outside ASCII could
// name one vehicle two ways.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>

namespace corridor::maps {

inline constexpr std::size_t kMaxIdLength = 64;

// nullopt for a valid id, else what is wrong with it, naming the character ("character 2 is 0x00,
// not printable ASCII (space to '~')").
[[nodiscard]] std::optional<std::string> id_problem(std::string_view id, std::size_t max_length = kMaxIdLength);

}  // namespace corridor::maps
