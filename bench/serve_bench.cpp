#include "bench/serve_bench.hpp"

#include <spdlog/spdlog.h>

#include <atomic>
#include <boost/asio.hpp>
#include <boost/beast.hpp>
#include <chrono>
#include <filesystem>
#include <random>
#include <stdexcept>
#include <thread>

#include "bench/replan_bench.hpp"
#include "server/http_server.hpp"

namespace corridor::bench {
namespace {

namespace beast = boost::beast;
namespace http = beast::http;
namespace net = boost::asio;
using tcp = net::ip::tcp;
using Clock = std::chrono::steady_clock;
using nlohmann::json;

const std::string kToken = "bench-token-0123456789abcdef";

// One keep-alive HTTP/1.1 connection with synchronous calls.
class Client {
 public:
  explicit Client(unsigned short port) : stream_(ioc_) { stream_.connect(tcp::endpoint(net::ip::make_address("127.0.0.1"), port)); }
  std::pair<int, std::string> post(const std::string& target, const std::string& body) {
    http::request<http::string_body> req{http::verb::post, target, 11};
    req.set(http::field::host, "127.0.0.1");
    req.set(http::field::authorization, "Bearer " + kToken);
    req.set(http::field::content_type, "application/json");
    req.keep_alive(true);
    req.body() = body;
    req.prepare_payload();
    http::write(stream_, req);
    http::response<http::string_body> res;
    http::read(stream_, buffer_, res);
    return {res.result_int(), res.body()};
  }

 private:
  net::io_context ioc_;
  beast::tcp_stream stream_;
  beast::flat_buffer buffer_;
};

json ll(const maps::RoadGraph& g, maps::Point2 p) {
  const maps::LatLon x = g.projection().to_lat_lon(p);
  return {{"lat", x.lat_deg}, {"lon", x.lon_deg}};
}

json latency_json(std::vector<double> ms) {
  const LatencySummary s = summarize_ms(std::move(ms));
  return {{"count", s.count}, {"p50_ms", s.p50_ms}, {"p95_ms", s.p95_ms}, {"max_ms", s.max_ms}, {"mean_ms", s.mean_ms}};
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(std::ceil(q * static_cast<double>(v.size()))) - 1)];
}

}  // namespace

json run_serve_bench(const maps::RoadGraph& graph, const ServeBenchConfig& c) {
  if (c.vehicles < 1 || c.missions < 0 || c.missions > c.vehicles || c.seconds <= 0 || c.client_threads < 1 ||
      c.congestion_requests_per_s < 1) {
    throw std::invalid_argument("bench serve: need vehicles >= missions >= 0, seconds > 0, threads >= 1");
  }
  const auto db = std::filesystem::temp_directory_path() / ("corridor-bench-" + std::to_string(::getpid()) + ".db");
  std::filesystem::remove(db);
  server::Store store(db);
  const auto now = [] { return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count(); };
  server::DispatchService service(graph, {}, &store, now());
  server::TokenAuth auth;
  auth.add(kToken, {"bench", server::kAllRoles, std::nullopt});
  server::Router router(service, std::move(auth), {}, now);
  server::HttpServer http(router, service, {}, "127.0.0.1", 0, c.server_threads);
  std::thread server_thread([&] { http.run(); });
  const unsigned short port = http.port();

  // Missions: random origin/destination pairs; each vehicle drives along its route's polyline.
  std::mt19937_64 rng(c.seed);
  std::vector<std::vector<json>> tracks(static_cast<std::size_t>(c.vehicles));
  {
    Client setup(port);
    std::uniform_int_distribution<std::uint32_t> any_node(0, static_cast<std::uint32_t>(graph.node_count() - 1));
    for (int v = 0; v < c.vehicles; ++v) {
      auto& track = tracks[static_cast<std::size_t>(v)];
      if (v >= c.missions) {
        track.push_back(ll(graph, graph.position(NodeId{any_node(rng)})));
        continue;
      }
      for (int attempt = 0; attempt < 20 && track.empty(); ++attempt) {
        const json body{{"vehicle_id", "v" + std::to_string(v)},
                        {"origin", ll(graph, graph.position(NodeId{any_node(rng)}))},
                        {"destination", ll(graph, graph.position(NodeId{any_node(rng)}))}};
        const auto [status, text] = setup.post("/v1/missions", body.dump());
        if (status != 201) continue;
        const json m = json::parse(text);
        for (const auto& p : m["route"]["geometry"]["coordinates"]) track.push_back({{"lat", p[1]}, {"lon", p[0]}});
      }
      if (track.empty()) throw std::runtime_error("bench serve: could not create mission for vehicle " + std::to_string(v));
    }
  }

  std::atomic<bool> stop{false};
  std::vector<std::vector<double>> position_ms(static_cast<std::size_t>(c.client_threads));
  std::atomic<std::uint64_t> errors{0};
  std::vector<std::thread> clients;
  const auto started = Clock::now();
  for (int t = 0; t < c.client_threads; ++t) {
    clients.emplace_back([&, t] {
      Client client(port);
      std::size_t step = 0;
      auto& samples = position_ms[static_cast<std::size_t>(t)];
      while (!stop.load(std::memory_order_relaxed)) {
        // Each thread serves every client_threads-th vehicle, in turn.
        for (int v = t; v < c.vehicles && !stop.load(std::memory_order_relaxed); v += c.client_threads) {
          const auto& track = tracks[static_cast<std::size_t>(v)];
          // Advance one route vertex every 20 reports and stop at 70 % of the route, so every mission
          // stays active for the whole run (a finished mission's positions cost nothing to plan).
          const std::size_t last = track.size() > 3 ? track.size() * 7 / 10 : 0;
          const json& p = track[std::min(step / 20, last)];
          json body{{"lat", p["lat"]}, {"lon", p["lon"]}, {"timestamp", static_cast<double>(step)}, {"source", "gps"}};
          const auto t0 = Clock::now();
          const auto [status, text] = client.post("/v1/vehicles/v" + std::to_string(v) + "/position", body.dump());
          samples.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
          if (status != 200) errors.fetch_add(1);
        }
        ++step;
      }
    });
  }
  std::vector<double> congestion_ms;
  std::thread sensor([&] {
    Client client(port);
    std::uniform_int_distribution<std::uint32_t> any_edge(0, static_cast<std::uint32_t>(graph.edge_count() - 1));
    std::uniform_real_distribution<double> factor(1.0, 4.0);
    const auto per_request = static_cast<int>(c.congestion_edges_per_s / c.congestion_requests_per_s);
    const auto period = std::chrono::duration<double>(1.0 / c.congestion_requests_per_s);
    auto next = Clock::now();
    while (!stop.load()) {
      json updates = json::array();
      for (int i = 0; i < per_request; ++i) updates.push_back({{"edge", any_edge(rng)}, {"factor", factor(rng)}, {"expires_in_s", 30}});
      const auto t0 = Clock::now();
      const auto [status, text] = client.post("/v1/congestion", json{{"updates", updates}}.dump());
      congestion_ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
      if (status != 200) errors.fetch_add(1);
      next += std::chrono::duration_cast<Clock::duration>(period);
      std::this_thread::sleep_until(next);
    }
  });
  std::this_thread::sleep_for(std::chrono::duration<double>(c.seconds));
  stop = true;
  for (auto& t : clients) t.join();
  sensor.join();
  const double elapsed = std::chrono::duration<double>(Clock::now() - started).count();

  // Server-side replan time per congestion request, from the service's own histogram.
  std::vector<double> all;
  for (auto& v : position_ms) all.insert(all.end(), v.begin(), v.end());
  const std::string metrics = router.metrics().render();
  http.stop();
  server_thread.join();
  std::filesystem::remove(db);
  std::filesystem::remove(db.string() + "-wal");
  std::filesystem::remove(db.string() + "-shm");

  json out;
  out["graph"] = {{"nodes", graph.node_count()}, {"edges", graph.edge_count()}};
  out["config"] = {{"vehicles", c.vehicles}, {"missions", c.missions}, {"congestion_edges_per_s", c.congestion_edges_per_s},
                   {"seconds", c.seconds}, {"client_threads", c.client_threads}, {"server_threads", c.server_threads}};
  out["positions"] = latency_json(all);
  out["positions"]["per_s"] = static_cast<double>(all.size()) / elapsed;
  out["positions"]["p99_ms"] = percentile(all, 0.99);
  out["congestion"] = latency_json(congestion_ms);
  out["congestion"]["p99_ms"] = percentile(congestion_ms, 0.99);
  out["congestion"]["edges_per_s"] = static_cast<double>(congestion_ms.size()) *
                                     (c.congestion_edges_per_s / c.congestion_requests_per_s) / elapsed;
  out["errors"] = errors.load();
  out["active_missions_at_end"] = service.active_mission_count();
  out["note"] = "client-side latency over loopback; clients and server share the machine's cores";
  (void)metrics;
  return out;
}

}  // namespace corridor::bench
