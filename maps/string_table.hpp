// Street names and refs as one interned string table in two flat arrays (CSR of characters), so
// the graph and its cache keep them without a pointer per edge. String 0 is the empty string.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

namespace corridor::maps {

struct StringTable {
  std::vector<char> chars;
  std::vector<std::uint32_t> first{0, 0};  // string i is chars[first[i] .. first[i+1])

  [[nodiscard]] std::size_t size() const { return first.empty() ? 0 : first.size() - 1; }
  [[nodiscard]] std::string_view at(std::uint32_t i) const {
    return {chars.data() + first[i], static_cast<std::size_t>(first[i + 1] - first[i])};
  }
};

// Builds a StringTable, giving equal strings one id.
class StringInterner {
 public:
  std::uint32_t intern(std::string_view s);
  [[nodiscard]] const StringTable& table() const { return table_; }
  StringTable take() { return std::move(table_); }

 private:
  StringTable table_;
  std::unordered_map<std::string, std::uint32_t> ids_{{std::string(), 0}};
};

inline std::uint32_t StringInterner::intern(std::string_view s) {
  if (s.empty()) return 0;
  auto [it, inserted] = ids_.try_emplace(std::string(s), static_cast<std::uint32_t>(table_.size()));
  if (inserted) {
    table_.chars.insert(table_.chars.end(), s.begin(), s.end());
    table_.first.push_back(static_cast<std::uint32_t>(table_.chars.size()));
  }
  return it->second;
}

}  // namespace corridor::maps
