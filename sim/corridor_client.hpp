// A small blocking HTTP/JSON client for a running `corridor serve` (Boost.Beast), so that the
// closed loop can drive the server's own mission, replanning and preemption loop.
#pragma once

#include <nlohmann/json.hpp>

#include <memory>
#include <string>
#include <string_view>

namespace corridor::sim {

// `text` as one segment of a URL path: every byte but RFC 3986's unreserved ones
// (A-Z a-z 0-9 - . _ ~) percent-encoded, so that an id such as "unit 7" or "a/b" names that id
// on the server (which decodes it) and not another path.
std::string path_segment(std::string_view text);

class CorridorClient {
 public:
  // `url` is http://host:port. Throws SimError for a URL it cannot use.
  CorridorClient(const std::string& url, std::string token);
  ~CorridorClient();
  CorridorClient(const CorridorClient&) = delete;
  CorridorClient& operator=(const CorridorClient&) = delete;

  // Sends one request (keeping the connection open) and returns the JSON body. Throws SimError
  // naming the method, path, status and the server's error message on any non-2xx answer, and on
  // a connection that fails twice.
  nlohmann::json get(const std::string& target);
  nlohmann::json post(const std::string& target, const nlohmann::json& body);

 private:
  struct Connection;
  nlohmann::json send(const std::string& method, const std::string& target, const std::string& body);

  std::string host_;
  std::string port_;
  std::string token_;
  std::unique_ptr<Connection> connection_;
};

}  // namespace corridor::sim
