// The SNMP side of `corridor signal-agent`: one command responder per intersection, each on its own
// UDP port, answering GET, GETNEXT, GETBULK and SET (v1, v2c and v3 with USM) for the objects of a
// VirtualIntersection. Net-SNMP parses and builds every message and runs USM (authentication,
// privacy, engine discovery and its reports); this class only answers the requests, as a command
// responder must (RFC 3416): exceptions or noSuchName for what is not there, SETs checked whole
// before any is applied, the read community refused a SET. An unknown community is dropped
// silently, as agents do. Single-threaded: poll() and the intersections' step() run on one thread.
#pragma once

#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "ntcip/virtual_intersection.hpp"

namespace corridor::ntcip {

class SnmpError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// An SNMPv3 user the agent accepts: SHA authentication and AES privacy (authPriv), the level
// agencies' networks ask for. Passwords are at least 8 characters (RFC 3414).
struct UsmUser {
  std::string name;
  std::string auth_password;
  std::string priv_password;
};

struct AgentSecurity {
  std::string read_community = "public";
  std::string write_community = "private";
  std::optional<UsmUser> v3_user;
  // Where the SNMP engine keeps its boot counter across restarts (a manager that saw the counter
  // fall would stop trusting the agent), and the engine's identity. One engine serves every port.
  std::filesystem::path state_dir;
  std::string engine_name = "corridor";  // becomes the text engine ID
};

class SnmpAgent {
 public:
  // Throws SnmpError when the library cannot start (a state directory that cannot be written, a
  // password under 8 characters). One SnmpAgent per process: Net-SNMP keeps one engine.
  explicit SnmpAgent(AgentSecurity security);
  ~SnmpAgent();
  SnmpAgent(const SnmpAgent&) = delete;
  SnmpAgent& operator=(const SnmpAgent&) = delete;

  // Serves `intersection` on host:port (UDP); the intersection must outlive the agent. Throws
  // SnmpError when the port cannot be bound.
  void serve(const std::string& host, unsigned short port, VirtualIntersection& intersection);
  // Waits up to timeout_ms for requests and answers every one that arrived, at time now_s.
  void poll(int timeout_ms, double now_s);
  [[nodiscard]] std::size_t requests_answered() const;

  struct Endpoint;  // one port's session and its intersection

 private:
  AgentSecurity security_;
  std::vector<std::unique_ptr<Endpoint>> endpoints_;
};

}  // namespace corridor::ntcip
