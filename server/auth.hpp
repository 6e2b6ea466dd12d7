// Bearer-token authentication with roles: dispatcher (missions), vehicle (positions of its own
// vehicle), sensor (congestion, detector counts), viewer (read and stream). Tokens are never logged.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <unordered_map>

#include <nlohmann/json.hpp>

namespace corridor::server {

enum class Role : std::uint8_t { dispatcher = 1, vehicle = 2, sensor = 4, viewer = 8 };
inline constexpr std::uint8_t kAllRoles = 0x0f;

struct Principal {
  std::string name;  // for logs, never the token
  std::uint8_t roles = 0;
  std::optional<std::string> vehicle_id;  // a vehicle token may only report for this vehicle

  [[nodiscard]] bool has(Role r) const { return (roles & static_cast<std::uint8_t>(r)) != 0; }
};

class AuthConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class TokenAuth {
 public:
  // Throws AuthConfigError for a token shorter than 16 characters or an unknown role.
  void add(const std::string& token, Principal principal);
  // {"tokens":[{"token":"…","name":"…","roles":["dispatcher",…],"vehicle_id":"…"}]}
  void add_from_config(const nlohmann::json& config);
  // The principal for an "Authorization: Bearer …" header, or nullopt.
  [[nodiscard]] std::optional<Principal> authenticate(std::string_view authorization) const;
  [[nodiscard]] std::size_t size() const { return tokens_.size(); }

 private:
  std::unordered_map<std::string, Principal> tokens_;
};

}  // namespace corridor::server
