// The HTTP API without the transport: one table of routes (method, path, roles, handler) that
// answers requests, renders errors as {"error":{"code","message"}}, counts metrics, and generates
// the OpenAPI description from the same table. Never throws, whatever the input.
#pragma once

#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include <nlohmann/json.hpp>

#include "server/auth.hpp"
#include "server/dispatch_service.hpp"
#include "server/metrics.hpp"
#include "server/static_site.hpp"
#include "server/stream_tickets.hpp"

namespace corridor::server {

struct HttpRequest {
  std::string method;
  std::string target;         // path and query
  std::string authorization;  // the Authorization header
  std::string body;
};

struct HttpResponse {
  int status = 200;
  std::string content_type = "application/json";
  std::string body;
  // Set while the request's writes are still on their way to the database: the response may be
  // sent only once this ticket is durable (and becomes a 503 if it fails).
  std::shared_ptr<CommitTicket> after_commit;
  // More headers (caching, security policy); the transport adds them as they are.
  std::vector<std::pair<std::string, std::string>> headers;
};

struct RouterConfig {
  double rate_per_token_per_s = 50000.0;  // token bucket refill
  double burst_per_token = 100000.0;
};

class Router {
 public:
  using Clock = std::function<double()>;  // seconds; wall clock in production, fake in tests

  // With `site`, paths outside the API (/v1/…, /metrics) are answered from it: the console.
  Router(DispatchService& service, TokenAuth auth, RouterConfig config, Clock clock,
         std::shared_ptr<const StaticSite> site = nullptr);
  ~Router();
  Router(const Router&) = delete;
  Router& operator=(const Router&) = delete;

  // Answers once the request's writes are durable; blocks until then.
  HttpResponse handle(const HttpRequest& request) noexcept;
  // Same answer, delivered through `reply` once durable: at once on the caller's thread, or later
  // on the commit thread. Never throws.
  void handle_async(const HttpRequest& request, std::function<void(HttpResponse)> reply) noexcept;
  // True for the routes that wait for their writes to be durable, or plan a whole route, before
  // they answer (creating and cancelling missions, congestion): a transport runs those off its
  // I/O threads, so that one of them cannot hold up the position reports behind it.
  [[nodiscard]] bool blocks(const HttpRequest& request) const noexcept;
  // For the WebSocket upgrade: the principal if it may read the stream, from a single-use
  // ?ticket= in the target (browsers) or else the Authorization header (other clients).
  [[nodiscard]] std::optional<Principal> authorize_stream(const std::string& authorization, const std::string& target);
  [[nodiscard]] nlohmann::json openapi() const;
  [[nodiscard]] Metrics& metrics() { return metrics_; }

 private:
  struct Match {
    std::vector<std::string> params;
    std::unordered_map<std::string, std::string> query;
  };
  using Handler = std::function<HttpResponse(const Principal&, const Match&, const HttpRequest&)>;
  struct Route {
    std::string method;
    std::string pattern;  // "/v1/missions/{id}"
    std::vector<std::string> segments;  // pattern split once, for matching
    std::uint8_t roles;   // any of these may call; 0 = no token needed
    std::string summary;
    Handler handler;
    bool blocking;  // see blocks()
  };

  void add(std::string method, std::string pattern, std::uint8_t roles, std::string summary, Handler handler,
           bool blocking = false);
  // The route for this method and path (its path parameters in `params`), or null; `path_known`
  // says whether the path exists for another method.
  const Route* match_route(const std::string& method, std::string_view path, std::vector<std::string>& params,
                           bool& path_known) const;
  bool take_token(const std::string& key, double now_s);
  HttpResponse json_response(int status, const nlohmann::json& body) const;
  // The answer, possibly still waiting on after_commit; records nothing in the metrics.
  HttpResponse answer(const HttpRequest& request, std::string& route_name) noexcept;
  HttpResponse storage_failure(const std::string& route_name, const std::string& error) const;

  DispatchService& service_;
  TokenAuth auth_;
  RouterConfig config_;
  Clock clock_;
  Metrics metrics_;
  std::vector<Route> routes_;
  std::string map_geojson_;  // rendered once: the graph never changes
  std::mutex buckets_mutex_;
  std::unordered_map<std::string, std::pair<double, double>> buckets_;  // token -> (tokens left, last refill)
  std::size_t subscription_ = 0;
  std::shared_ptr<const StaticSite> site_;
  StreamTickets tickets_;
};

}  // namespace corridor::server
