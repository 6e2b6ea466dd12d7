// Short-lived, single-use tickets for the WebSocket stream. A browser cannot set an Authorization
// header on a WebSocket, and a long-lived token in a URL ends up in logs and history; so a client
// trades its token for a ticket over an authenticated POST, and opens the stream with
// ?ticket=… within the ticket's lifetime. The ticket is redeemed once.
#pragma once

#include <cstddef>
#include <mutex>
#include <optional>
#include <random>
#include <string>
#include <unordered_map>

#include "server/auth.hpp"

namespace corridor::server {

struct StreamTicketConfig {
  double lifetime_s = 30.0;
  std::size_t max_outstanding = 10000;  // past this, the oldest unredeemed tickets are dropped
};

class StreamTickets {
 public:
  explicit StreamTickets(StreamTicketConfig config = {});

  // A fresh ticket (32 hex digits, 128 random bits) for this principal.
  std::string issue(const Principal& who, double now_s);
  // The principal, once: a second redeem, an unknown or an expired ticket gives nullopt.
  std::optional<Principal> redeem(const std::string& ticket, double now_s);

  [[nodiscard]] const StreamTicketConfig& config() const { return config_; }

 private:
  struct Entry {
    Principal who;
    double expires_s;
  };
  void purge(double now_s);

  StreamTicketConfig config_;
  std::mutex mutex_;
  std::random_device entropy_;
  std::unordered_map<std::string, Entry> tickets_;
};

}  // namespace corridor::server
