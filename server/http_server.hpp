// The HTTP/WebSocket transport (Boost.Beast over Asio): accepts connections, enforces size limits
// and timeouts, hands each request to the Router, and streams dispatch events to WebSocket clients
// on GET /v1/stream. Each connection lives on one single-threaded io_context; the Router and
// service do the rest.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "server/router.hpp"

namespace corridor::server {

struct ServerLimits {
  std::size_t body_limit_bytes = 1 << 20;
  std::size_t header_limit_bytes = 16 << 10;
  int read_timeout_s = 30;
  std::size_t max_queued_events = 4096;  // a WebSocket client this far behind is disconnected
  // Nice steps (0..19) the I/O threads (position reports, the event stream) take below the workers
  // that plan and repair routes: as DispatchConfig::background_nice, for the same reason.
  int io_nice = 10;
};

class HttpServer {
 public:
  // Binds at once (port 0 picks a free port). Throws std::system_error when the address is taken,
  // std::invalid_argument when limits.io_nice is outside 0..19.
  HttpServer(Router& router, DispatchService& service, ServerLimits limits, const std::string& address,
             unsigned short port, int threads);
  ~HttpServer();
  HttpServer(const HttpServer&) = delete;
  HttpServer& operator=(const HttpServer&) = delete;

  [[nodiscard]] unsigned short port() const;
  // Runs until stop(), SIGINT or SIGTERM, on `threads` threads of its own, one io_context each
  // (the calling thread waits for them, its priority untouched); ticks the service once a second.
  void run();
  void stop();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace corridor::server
