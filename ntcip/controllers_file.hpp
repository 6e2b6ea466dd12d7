// The field controllers a server drives (`corridor serve --controllers FILE.json`), and the
// manifest `corridor signal-agent` writes, which is such a file as it is: a JSON array with one
// object per controller, naming its intersection (osm_node_id on an OSM map, tls_id on a SUMO
// network), where it answers, how to authenticate, and how the intersection is wired: each
// approach (or turning movement) to a preempt input, or to the NTCIP phases that serve it for
// priority without preemption. Read and validated whole at start; every error names its field.
#pragma once

#include <nlohmann/json.hpp>

#include <cstdint>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "maps/signal_plan.hpp"

namespace corridor::ntcip {

// A file that is not a valid controllers file; the message names the field, e.g.
// "controllers[2].preempts[0].approach: must be one of N, E, S, W".
class ControllersFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class SnmpVersion { v1, v2c, v3 };
enum class SecurityLevel { no_auth_no_priv, auth_no_priv, auth_priv };

struct SnmpCredentials {
  SnmpVersion version = SnmpVersion::v2c;
  std::string read_community = "public";  // v1, v2c
  std::string write_community = "private";
  // v3 (USM)
  std::string user;
  SecurityLevel level = SecurityLevel::auth_priv;
  std::string auth_protocol = "SHA";  // SHA, SHA-256, MD5
  std::string auth_password;
  std::string priv_protocol = "AES";  // AES, DES
  std::string priv_password;
};

struct PreemptWiring {
  std::uint32_t number = 1;
  maps::Compass approach = maps::Compass::north;
  std::optional<std::string> movement;  // "E->N": the input serves that movement only
};

struct PhaseControlWiring {
  maps::Compass approach = maps::Compass::north;
  std::optional<std::string> movement;
  std::vector<std::uint32_t> phases;  // NTCIP phase numbers that serve it
};

// Which plan movement an NTCIP phase number stands for, so that what the controller reports on show
// (phaseStatusGroupGreens) reads as the plan's lights.
struct PhaseWiring {
  std::uint32_t number = 1;
  std::string movement;  // "N->S"
};

// When a hold is a preempt call and when it is priority by phase control.
enum class PriorityMode { preempt, phase_control, by_priority };

struct ControllerConfig {
  std::string id;  // printable, unique; defaults to the intersection's name
  std::optional<std::int64_t> osm_node_id;
  std::optional<std::string> tls_id;
  std::string host = "127.0.0.1";
  std::uint16_t port = 161;
  SnmpCredentials snmp;
  double timeout_s = 0.5;  // per try
  int retries = 1;
  double keepalive_s = 2.0;  // a held call is re-asserted this often
  double poll_s = 1.0;       // the controller's state is read this often
  std::vector<PreemptWiring> preempts;
  std::vector<PhaseControlWiring> phase_control;
  std::vector<PhaseWiring> phases;
  PriorityMode mode = PriorityMode::by_priority;
  int preempt_min_priority = 2;  // by_priority: missions of at least this priority preempt
  // The manifest's description of a virtual controller (informative).
  std::vector<std::pair<std::uint32_t, std::uint32_t>> conflicts;  // NTCIP phases never green together
  std::string description;
};

// Throws ControllersFileError for a file that cannot be read or is not a valid controllers file.
std::vector<ControllerConfig> read_controllers_file(const std::filesystem::path& file);
std::vector<ControllerConfig> parse_controllers(const nlohmann::json& j);
nlohmann::json to_json(const std::vector<ControllerConfig>& controllers);

[[nodiscard]] const char* to_string(maps::Compass c);  // "N", "E", "S", "W"

}  // namespace corridor::ntcip
