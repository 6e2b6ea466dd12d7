#include "ntcip/controllers_file.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <set>

#include "maps/text_id.hpp"

namespace corridor::ntcip {
namespace {

using nlohmann::json;

[[noreturn]] void fail(const std::string& where, const std::string& what) { throw ControllersFileError(where + ": " + what); }

void only_keys(const json& j, const std::string& where, std::initializer_list<const char*> keys) {
  for (const auto& item : j.items()) {
    const std::string& key = item.key();
    if (std::find_if(keys.begin(), keys.end(), [&](const char* k) { return key == k; }) == keys.end()) {
      fail(where + "." + key, "unknown field");
    }
  }
}

std::string text(const json& j, const std::string& where, const char* key, bool required, std::string fallback = {}) {
  const auto it = j.find(key);
  if (it == j.end()) {
    if (required) fail(where + "." + key, "is required");
    return fallback;
  }
  if (!it->is_string()) fail(where + "." + key, "must be a string");
  return it->get<std::string>();
}

double number(const json& j, const std::string& where, const char* key, double fallback, double lo, double hi) {
  const auto it = j.find(key);
  if (it == j.end()) return fallback;
  if (!it->is_number()) fail(where + "." + key, "must be a number");
  const double v = it->get<double>();
  if (!std::isfinite(v) || v < lo || v > hi) fail(where + "." + key, fmt::format("must be within [{:g}, {:g}]", lo, hi));
  return v;
}

std::int64_t integer(const json& j, const std::string& where, const char* key, std::int64_t lo, std::int64_t hi) {
  if (!j.is_number_integer()) fail(where + (key[0] != '\0' ? std::string(".") + key : std::string()), "must be an integer");
  const auto v = j.get<std::int64_t>();
  if (v < lo || v > hi) fail(where + (key[0] != '\0' ? std::string(".") + key : std::string()), fmt::format("must be within [{}, {}]", lo, hi));
  return v;
}

maps::Compass approach(const json& j, const std::string& where) {
  const std::string a = text(j, where, "approach", true);
  if (a == "N") return maps::Compass::north;
  if (a == "E") return maps::Compass::east;
  if (a == "S") return maps::Compass::south;
  if (a == "W") return maps::Compass::west;
  fail(where + ".approach", "must be one of N, E, S, W, not '" + a + "'");
}

std::optional<std::string> movement(const json& j, const std::string& where, const char* key = "movement") {
  if (!j.contains(key)) return std::nullopt;
  const std::string m = text(j, where, key, true);
  // "N->S": from and to sides.
  const auto side = [](char c) { return c == 'N' || c == 'E' || c == 'S' || c == 'W'; };
  if (m.size() != 4 || !side(m[0]) || m[1] != '-' || m[2] != '>' || !side(m[3])) {
    fail(where + "." + key, "must be a movement like N->S (from side, to side), not '" + m + "'");
  }
  return m;
}

std::string password(const json& j, const std::string& where, const char* key) {
  const std::string p = text(j, where, key, true);
  if (p.size() < 8) fail(where + "." + key, "must be at least 8 characters (RFC 3414)");
  return p;
}

SnmpCredentials credentials(const json& j, const std::string& where) {
  SnmpCredentials c;
  if (!j.is_object()) fail(where, "must be an object");
  only_keys(j, where, {"version", "read_community", "write_community", "user", "security_level", "auth_protocol",
                       "auth_password", "priv_protocol", "priv_password"});
  const std::string version = text(j, where, "version", false, "v2c");
  if (version == "v1") c.version = SnmpVersion::v1;
  else if (version == "v2c") c.version = SnmpVersion::v2c;
  else if (version == "v3") c.version = SnmpVersion::v3;
  else fail(where + ".version", "must be v1, v2c or v3, not '" + version + "'");
  if (c.version != SnmpVersion::v3) {
    c.read_community = text(j, where, "read_community", false, "public");
    c.write_community = text(j, where, "write_community", false, "private");
    for (const auto& [key, value] : {std::pair<const char*, std::string>{"read_community", c.read_community},
                                     std::pair<const char*, std::string>{"write_community", c.write_community}}) {
      if (const auto problem = maps::id_problem(value, 255)) fail(where + "." + key, *problem);
    }
    for (const char* key : {"user", "auth_password", "priv_password"}) {
      if (j.contains(key)) fail(where + "." + key, "is for version v3");
    }
    return c;
  }
  c.user = text(j, where, "user", true);
  if (const auto problem = maps::id_problem(c.user, 32)) fail(where + ".user", *problem);
  const std::string level = text(j, where, "security_level", false, "authPriv");
  if (level == "authPriv") c.level = SecurityLevel::auth_priv;
  else if (level == "authNoPriv") c.level = SecurityLevel::auth_no_priv;
  else if (level == "noAuthNoPriv") c.level = SecurityLevel::no_auth_no_priv;
  else fail(where + ".security_level", "must be authPriv, authNoPriv or noAuthNoPriv, not '" + level + "'");
  if (c.level != SecurityLevel::no_auth_no_priv) {
    c.auth_protocol = text(j, where, "auth_protocol", false, "SHA");
    if (c.auth_protocol != "SHA" && c.auth_protocol != "SHA-256" && c.auth_protocol != "MD5") {
      fail(where + ".auth_protocol", "must be SHA, SHA-256 or MD5, not '" + c.auth_protocol + "'");
    }
    c.auth_password = password(j, where, "auth_password");
  }
  if (c.level == SecurityLevel::auth_priv) {
    c.priv_protocol = text(j, where, "priv_protocol", false, "AES");
    if (c.priv_protocol != "AES" && c.priv_protocol != "DES") fail(where + ".priv_protocol", "must be AES or DES, not '" + c.priv_protocol + "'");
    c.priv_password = password(j, where, "priv_password");
  }
  return c;
}

ControllerConfig controller(const json& j, const std::string& where) {
  if (!j.is_object()) fail(where, "must be an object");
  only_keys(j, where, {"id", "osm_node_id", "tls_id", "host", "port", "snmp", "timeout_s", "retries", "keepalive_s", "poll_s",
                       "preempts", "phase_control", "phases", "priority_mode", "preempt_min_priority", "conflicts",
                       "description", "signal"});
  ControllerConfig c;
  if (j.contains("osm_node_id")) c.osm_node_id = integer(j.at("osm_node_id"), where, "osm_node_id", 1, INT64_MAX);
  if (j.contains("tls_id")) {
    c.tls_id = text(j, where, "tls_id", true);
    if (const auto problem = maps::id_problem(*c.tls_id, 255)) fail(where + ".tls_id", *problem);
  }
  if (c.osm_node_id.has_value() == c.tls_id.has_value()) fail(where, "give exactly one of osm_node_id (an OSM map) and tls_id (a SUMO network)");
  c.id = text(j, where, "id", false, c.tls_id ? *c.tls_id : std::to_string(*c.osm_node_id));
  if (const auto problem = maps::id_problem(c.id)) fail(where + ".id", *problem);
  c.host = text(j, where, "host", false, "127.0.0.1");
  if (c.host.empty() || c.host.find_first_of(" :/") != std::string::npos || maps::id_problem(c.host, 253)) {
    fail(where + ".host", "must be a host name or an IPv4 address, not '" + c.host + "'");
  }
  if (!j.contains("port")) fail(where + ".port", "is required");
  c.port = static_cast<std::uint16_t>(integer(j.at("port"), where, "port", 1, 65535));
  if (j.contains("snmp")) c.snmp = credentials(j.at("snmp"), where + ".snmp");
  c.timeout_s = number(j, where, "timeout_s", c.timeout_s, 0.05, 30.0);
  if (j.contains("retries")) c.retries = static_cast<int>(integer(j.at("retries"), where, "retries", 0, 10));
  c.keepalive_s = number(j, where, "keepalive_s", c.keepalive_s, 0.2, 60.0);
  c.poll_s = number(j, where, "poll_s", c.poll_s, 0.1, 60.0);
  const auto list = [&](const char* key) -> const json& {
    static const json empty = json::array();
    if (!j.contains(key)) return empty;
    if (!j.at(key).is_array()) fail(where + "." + key, "must be an array");
    return j.at(key);
  };
  std::set<std::uint32_t> numbers;
  for (std::size_t i = 0; i < list("preempts").size(); ++i) {
    const json& p = list("preempts")[i];
    const std::string at = fmt::format("{}.preempts[{}]", where, i);
    if (!p.is_object()) fail(at, "must be an object");
    only_keys(p, at, {"number", "approach", "movement"});
    if (!p.contains("number")) fail(at + ".number", "is required");
    PreemptWiring w;
    w.number = static_cast<std::uint32_t>(integer(p.at("number"), at, "number", 1, 255));
    if (!numbers.insert(w.number).second) fail(at + ".number", fmt::format("preempt {} is wired twice", w.number));
    w.approach = approach(p, at);
    w.movement = movement(p, at);
    if (w.movement && w.movement->front() != to_string(w.approach)[0]) fail(at + ".movement", "must start from its approach");
    c.preempts.push_back(std::move(w));
  }
  for (std::size_t i = 0; i < list("phase_control").size(); ++i) {
    const json& p = list("phase_control")[i];
    const std::string at = fmt::format("{}.phase_control[{}]", where, i);
    if (!p.is_object()) fail(at, "must be an object");
    only_keys(p, at, {"approach", "movement", "phases"});
    PhaseControlWiring w;
    w.approach = approach(p, at);
    w.movement = movement(p, at);
    if (!p.contains("phases") || !p.at("phases").is_array() || p.at("phases").empty()) fail(at + ".phases", "must be a non-empty array of phase numbers");
    for (std::size_t k = 0; k < p.at("phases").size(); ++k) {
      w.phases.push_back(static_cast<std::uint32_t>(integer(p.at("phases")[k], fmt::format("{}.phases[{}]", at, k), "", 1, 255)));
    }
    c.phase_control.push_back(std::move(w));
  }
  std::set<std::uint32_t> phase_numbers;
  for (std::size_t i = 0; i < list("phases").size(); ++i) {
    const json& p = list("phases")[i];
    const std::string at = fmt::format("{}.phases[{}]", where, i);
    if (!p.is_object()) fail(at, "must be an object");
    only_keys(p, at, {"number", "movement"});
    if (!p.contains("number")) fail(at + ".number", "is required");
    PhaseWiring w;
    w.number = static_cast<std::uint32_t>(integer(p.at("number"), at, "number", 1, 255));
    if (!phase_numbers.insert(w.number).second) fail(at + ".number", fmt::format("phase {} is listed twice", w.number));
    const auto m = movement(p, at);
    if (!m) fail(at + ".movement", "is required");
    w.movement = *m;
    c.phases.push_back(std::move(w));
  }
  for (std::size_t i = 0; i < list("conflicts").size(); ++i) {
    const json& p = list("conflicts")[i];
    const std::string at = fmt::format("{}.conflicts[{}]", where, i);
    if (!p.is_array() || p.size() != 2) fail(at, "must be a pair of phase numbers");
    c.conflicts.emplace_back(static_cast<std::uint32_t>(integer(p[0], at + "[0]", "", 1, 255)),
                             static_cast<std::uint32_t>(integer(p[1], at + "[1]", "", 1, 255)));
  }
  const std::string mode = text(j, where, "priority_mode", false, "by_priority");
  if (mode == "preempt") c.mode = PriorityMode::preempt;
  else if (mode == "phase_control") c.mode = PriorityMode::phase_control;
  else if (mode == "by_priority") c.mode = PriorityMode::by_priority;
  else fail(where + ".priority_mode", "must be preempt, phase_control or by_priority, not '" + mode + "'");
  if (j.contains("preempt_min_priority")) {
    c.preempt_min_priority = static_cast<int>(integer(j.at("preempt_min_priority"), where, "preempt_min_priority", 0, 100));
  }
  if (c.mode != PriorityMode::phase_control && c.preempts.empty()) {
    fail(where + ".preempts", "must wire at least one preempt input (or set priority_mode to phase_control)");
  }
  if (c.mode != PriorityMode::preempt && c.phase_control.empty() && c.mode == PriorityMode::phase_control) {
    fail(where + ".phase_control", "must wire at least one approach to its phases for priority_mode phase_control");
  }
  c.description = text(j, where, "description", false);
  return c;
}

}  // namespace

const char* to_string(maps::Compass c) {
  switch (c) {
    case maps::Compass::north: return "N";
    case maps::Compass::east: return "E";
    case maps::Compass::south: return "S";
    case maps::Compass::west: return "W";
  }
  return "?";
}

std::vector<ControllerConfig> parse_controllers(const json& j) {
  if (!j.is_array()) throw ControllersFileError("controllers: the file must be a JSON array, one object per controller");
  std::vector<ControllerConfig> out;
  std::set<std::string> ids, intersections, endpoints;
  for (std::size_t i = 0; i < j.size(); ++i) {
    const std::string where = fmt::format("controllers[{}]", i);
    ControllerConfig c = controller(j[i], where);
    if (!ids.insert(c.id).second) fail(where + ".id", "'" + c.id + "' is used twice");
    const std::string intersection = c.tls_id ? "tls " + *c.tls_id : "node " + std::to_string(*c.osm_node_id);
    if (!intersections.insert(intersection).second) fail(where, "the intersection (" + intersection + ") has two controllers");
    if (!endpoints.insert(c.host + ":" + std::to_string(c.port)).second) {
      fail(where + ".port", c.host + ":" + std::to_string(c.port) + " is another controller's");
    }
    out.push_back(std::move(c));
  }
  return out;
}

std::vector<ControllerConfig> read_controllers_file(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw ControllersFileError("cannot read the controllers file '" + file.string() + "'");
  json j;
  try {
    j = json::parse(in);
  } catch (const json::exception& e) {  // a syntax error, or a number too large for a double (406)
    throw ControllersFileError("'" + file.string() + "' is not JSON: " + e.what());
  }
  try {
    return parse_controllers(j);
  } catch (const ControllersFileError& e) {
    throw ControllersFileError("'" + file.string() + "': " + e.what());
  }
}

json to_json(const std::vector<ControllerConfig>& controllers) {
  json out = json::array();
  for (const ControllerConfig& c : controllers) {
    json j{{"id", c.id}, {"host", c.host}, {"port", c.port}};
    if (c.osm_node_id) j["osm_node_id"] = *c.osm_node_id;
    if (c.tls_id) j["tls_id"] = *c.tls_id;
    json snmp;
    switch (c.snmp.version) {
      case SnmpVersion::v1:
      case SnmpVersion::v2c:
        snmp = {{"version", c.snmp.version == SnmpVersion::v1 ? "v1" : "v2c"}, {"read_community", c.snmp.read_community},
                {"write_community", c.snmp.write_community}};
        break;
      case SnmpVersion::v3:
        snmp = {{"version", "v3"}, {"user", c.snmp.user},
                {"security_level", c.snmp.level == SecurityLevel::auth_priv      ? "authPriv"
                                   : c.snmp.level == SecurityLevel::auth_no_priv ? "authNoPriv"
                                                                                 : "noAuthNoPriv"}};
        if (c.snmp.level != SecurityLevel::no_auth_no_priv) {
          snmp["auth_protocol"] = c.snmp.auth_protocol;
          snmp["auth_password"] = c.snmp.auth_password;
        }
        if (c.snmp.level == SecurityLevel::auth_priv) {
          snmp["priv_protocol"] = c.snmp.priv_protocol;
          snmp["priv_password"] = c.snmp.priv_password;
        }
        break;
    }
    j["snmp"] = std::move(snmp);
    j["timeout_s"] = c.timeout_s;
    j["retries"] = c.retries;
    j["keepalive_s"] = c.keepalive_s;
    j["poll_s"] = c.poll_s;
    json preempts = json::array();
    for (const auto& p : c.preempts) {
      json w{{"number", p.number}, {"approach", to_string(p.approach)}};
      if (p.movement) w["movement"] = *p.movement;
      preempts.push_back(std::move(w));
    }
    j["preempts"] = std::move(preempts);
    if (!c.phase_control.empty()) {
      json pc = json::array();
      for (const auto& p : c.phase_control) {
        json w{{"approach", to_string(p.approach)}, {"phases", p.phases}};
        if (p.movement) w["movement"] = *p.movement;
        pc.push_back(std::move(w));
      }
      j["phase_control"] = std::move(pc);
    }
    if (!c.phases.empty()) {
      json ph = json::array();
      for (const auto& p : c.phases) ph.push_back({{"number", p.number}, {"movement", p.movement}});
      j["phases"] = std::move(ph);
    }
    j["priority_mode"] = c.mode == PriorityMode::preempt ? "preempt" : c.mode == PriorityMode::phase_control ? "phase_control" : "by_priority";
    j["preempt_min_priority"] = c.preempt_min_priority;
    if (!c.conflicts.empty()) {
      json conflicts = json::array();
      for (const auto& [a, b] : c.conflicts) conflicts.push_back({a, b});
      j["conflicts"] = std::move(conflicts);
    }
    if (!c.description.empty()) j["description"] = c.description;
    out.push_back(std::move(j));
  }
  return out;
}

}  // namespace corridor::ntcip
