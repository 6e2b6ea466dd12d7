#include "maps/text_id.hpp"

#include <fmt/format.h>

namespace corridor::maps {

std::optional<std::string> id_problem(std::string_view id, std::size_t max_length) {
  if (id.empty()) return std::string("is empty");
  if (id.size() > max_length) return fmt::format("is {} characters long, more than {}", id.size(), max_length);
  for (std::size_t i = 0; i < id.size(); ++i) {
    const auto c = static_cast<unsigned char>(id[i]);
    if (c < 0x20 || c > 0x7e) return fmt::format("character {} is 0x{:02x}, not printable ASCII (space to '~')", i + 1, c);
  }
  if (id.front() == ' ' || id.back() == ' ') return std::string("begins or ends with a space");
  return std::nullopt;
}

}  // namespace corridor::maps
