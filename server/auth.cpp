#include "server/auth.hpp"

#include "maps/text_id.hpp"

namespace corridor::server {

void TokenAuth::add(const std::string& token, Principal principal) {
  if (token.size() < 16) throw AuthConfigError("token for '" + principal.name + "' is shorter than 16 characters");
  // A token travels in an Authorization header: printable, no space.
  if (const auto problem = maps::id_problem(token, 256); problem || token.find(' ') != std::string::npos) {
    throw AuthConfigError("token for '" + principal.name + "': " + (problem ? "the token " + *problem : std::string("the token has a space")));
  }
  if (const auto problem = maps::id_problem(principal.name)) throw AuthConfigError("token name '" + principal.name + "': " + *problem);
  if (principal.vehicle_id) {
    if (const auto problem = maps::id_problem(*principal.vehicle_id)) {
      throw AuthConfigError("token '" + principal.name + "': vehicle_id " + *problem);
    }
  }
  if (principal.roles == 0 || (principal.roles & ~kAllRoles) != 0) {
    throw AuthConfigError("token for '" + principal.name + "' needs at least one known role");
  }
  // A vehicle token reports for its own vehicle only; without a dispatcher's role it must say which.
  const bool dispatcher = (principal.roles & static_cast<std::uint8_t>(Role::dispatcher)) != 0;
  const bool vehicle = (principal.roles & static_cast<std::uint8_t>(Role::vehicle)) != 0;
  if (vehicle && !dispatcher && (!principal.vehicle_id || principal.vehicle_id->empty())) {
    throw AuthConfigError("token for '" + principal.name + "' has the vehicle role and needs a 'vehicle_id'");
  }
  tokens_[token] = std::move(principal);
}

void TokenAuth::add_from_config(const nlohmann::json& config) {
  auto it = config.find("tokens");
  if (it == config.end()) return;
  if (!it->is_array()) throw AuthConfigError("config: 'tokens' must be an array");
  for (const auto& t : *it) {
    if (!t.is_object() || !t.contains("token") || !t["token"].is_string()) {
      throw AuthConfigError("config: every token needs a string 'token'");
    }
    Principal p;
    if (t.contains("name") && !t["name"].is_string()) throw AuthConfigError("config: a token's 'name' must be a string");
    p.name = t.value("name", std::string("unnamed"));
    if (!t.contains("roles") || !t["roles"].is_array()) throw AuthConfigError("config: token '" + p.name + "' needs 'roles'");
    for (const auto& r : t["roles"]) {
      const std::string role = r.is_string() ? r.get<std::string>() : "";
      if (role == "dispatcher") p.roles |= static_cast<std::uint8_t>(Role::dispatcher);
      else if (role == "vehicle") p.roles |= static_cast<std::uint8_t>(Role::vehicle);
      else if (role == "sensor") p.roles |= static_cast<std::uint8_t>(Role::sensor);
      else if (role == "viewer") p.roles |= static_cast<std::uint8_t>(Role::viewer);
      else throw AuthConfigError("config: token '" + p.name + "' has unknown role '" + role + "'");
    }
    if (t.contains("vehicle_id")) {
      if (!t["vehicle_id"].is_string()) throw AuthConfigError("config: 'vehicle_id' must be a string");
      p.vehicle_id = t["vehicle_id"].get<std::string>();
    }
    add(t["token"].get<std::string>(), std::move(p));
  }
}

std::optional<Principal> TokenAuth::authenticate(std::string_view authorization) const {
  constexpr std::string_view kBearer = "Bearer ";
  if (authorization.size() <= kBearer.size() || authorization.substr(0, kBearer.size()) != kBearer) return std::nullopt;
  auto it = tokens_.find(std::string(authorization.substr(kBearer.size())));
  if (it == tokens_.end()) return std::nullopt;
  return it->second;
}

}  // namespace corridor::server
