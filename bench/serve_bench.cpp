#include "bench/serve_bench.hpp"

#include <spdlog/fmt/fmt.h>
#include <spdlog/spdlog.h>

#include <boost/asio.hpp>
#include <boost/beast.hpp>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <optional>
#include <random>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "bench/replan_bench.hpp"
#include "server/http_server.hpp"

namespace corridor::bench {
namespace {

// Resident set size of this process in MiB, from /proc/self/status (0 where it cannot be read).
double resident_mb() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("VmRSS:", 0) == 0) return std::strtod(line.c_str() + 6, nullptr) / 1024.0;
  }
  return 0.0;
}

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
    return call(http::verb::post, target, body);
  }
  std::pair<int, std::string> get(const std::string& target) { return call(http::verb::get, target, ""); }

 private:
  std::pair<int, std::string> call(http::verb verb, const std::string& target, const std::string& body) {
    http::request<http::string_body> req{verb, target, 11};
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

  net::io_context ioc_;
  beast::tcp_stream stream_;
  beast::flat_buffer buffer_;
};

// One keep-alive connection that posts bodies back to back (period 0) or on a fixed schedule.
// A paced request's latency counts from its scheduled send time, so a server that falls behind
// cannot hide its queueing (no coordinated omission). Each connection runs one chain of
// operations at a time, so it needs no strand even with several client threads.
//
// The load generator shares the cores with the server it measures, so it writes each request as
// one preformatted buffer, like wrk, rather than building and serializing a message each time.
class LoadConnection {
 public:
  LoadConnection(net::io_context& ioc, unsigned short port, const std::string& target,
                 std::function<std::string()> next_body, double period_s, Clock::time_point deadline,
                 Clock::time_point first)
      : socket_(ioc),
        timer_(ioc),
        next_body_(std::move(next_body)),
        period_(std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(period_s))),
        deadline_(deadline),
        due_(first),
        head_("POST " + target + " HTTP/1.1\r\nHost: 127.0.0.1\r\nAuthorization: Bearer " + kToken +
              "\r\nContent-Type: application/json\r\nContent-Length: ") {
    socket_.connect(tcp::endpoint(net::ip::make_address("127.0.0.1"), port));
    socket_.set_option(tcp::no_delay(true));
  }
  void start() { schedule(); }
  // Sees each successful response's body (on the client thread that read it).
  void on_body(std::function<void(const std::string&)> f) { on_body_ = std::move(f); }
  [[nodiscard]] const std::vector<double>& latencies_ms() const { return latencies_ms_; }
  // How late each request left against its schedule: the load generator's own share of the latency.
  [[nodiscard]] const std::vector<double>& send_lags_ms() const { return send_lags_ms_; }
  // From each request leaving to its answer: the server's and the kernel's share, without the
  // generator's lateness (what a load generator that waits for its own schedule would report).
  [[nodiscard]] const std::vector<double>& after_send_ms() const { return after_send_ms_; }
  [[nodiscard]] std::uint64_t errors() const { return errors_; }

 private:
  void schedule() {
    const auto now = Clock::now();
    if (period_ == Clock::duration::zero()) due_ = now;
    if (due_ >= deadline_) return;
    if (due_ <= now) return send();
    timer_.expires_at(due_);
    timer_.async_wait([this](boost::system::error_code ec) {
      if (!ec) send();
    });
  }
  void send() {
    sent_ = Clock::now();
    send_lags_ms_.push_back(std::chrono::duration<double, std::milli>(sent_ - due_).count());
    const std::string body = next_body_();
    out_.assign(head_).append(std::to_string(body.size())).append("\r\n\r\n").append(body);
    net::async_write(socket_, net::buffer(out_), [this](boost::system::error_code ec, std::size_t) {
      if (ec) return fail();
      res_ = {};
      http::async_read(socket_, buffer_, res_, [this](beast::error_code read_ec, std::size_t) {
        if (read_ec) return fail();
        const auto now = Clock::now();
        latencies_ms_.push_back(std::chrono::duration<double, std::milli>(now - due_).count());
        after_send_ms_.push_back(std::chrono::duration<double, std::milli>(now - sent_).count());
        if (res_.result_int() != 200) {
          ++errors_;
        } else if (on_body_) {
          on_body_(res_.body());
        }
        due_ += period_;
        schedule();
      });
    });
  }
  void fail() { ++errors_; }  // the connection is gone; this vehicle stops reporting

  tcp::socket socket_;
  net::steady_timer timer_;
  std::function<std::string()> next_body_;
  std::function<void(const std::string&)> on_body_;
  Clock::duration period_;
  Clock::time_point deadline_;
  Clock::time_point due_;
  Clock::time_point sent_;
  const std::string head_;
  std::string out_;
  beast::flat_buffer buffer_;
  http::response<http::string_body> res_;
  std::vector<double> latencies_ms_;
  std::vector<double> send_lags_ms_;
  std::vector<double> after_send_ms_;
  std::uint64_t errors_ = 0;
};

json ll(const maps::RoadGraph& g, maps::Point2 p) {
  const maps::LatLon x = g.projection().to_lat_lon(p);
  return {{"lat", x.lat_deg}, {"lon", x.lon_deg}};
}

json latency_json(std::vector<double> ms) { return to_json(summarize_ms(std::move(ms))); }

// A Prometheus histogram (with these labels) read back from the server's /metrics: how many
// samples, the share within each bucket bound, and the smallest bound that holds 99 % of them (an
// upper bound of the p99).
json histogram_from_metrics(const std::string& text, const std::string& name, const std::string& labels = "") {
  std::vector<std::pair<double, double>> buckets;  // (le, cumulative count)
  double count = 0;
  std::istringstream in(text);
  std::string line;
  const std::string bucket_prefix = name + "_bucket{" + labels + (labels.empty() ? "" : ",") + "le=\"";
  const std::string count_prefix = name + "_count{" + labels + "} ";
  while (std::getline(in, line)) {
    if (line.rfind(bucket_prefix, 0) == 0) {
      const auto close = line.find('"', bucket_prefix.size());
      const std::string le = line.substr(bucket_prefix.size(), close - bucket_prefix.size());
      if (le != "+Inf") buckets.emplace_back(std::stod(le), std::stod(line.substr(line.rfind(' ') + 1)));
    } else if (line.rfind(count_prefix, 0) == 0) {
      count = std::stod(line.substr(count_prefix.size()));
    }
  }
  json out{{"count", static_cast<std::uint64_t>(count)}};
  json within = json::array();
  std::optional<double> p99_bound;
  for (const auto& [le, cumulative] : buckets) {
    if (count > 0) within.push_back({{"le_ms", le * 1e3}, {"share", cumulative / count}});
    if (!p99_bound && count > 0 && cumulative >= 0.99 * count) p99_bound = le * 1e3;
  }
  out["share_within"] = std::move(within);
  out["p99_at_most_ms"] = p99_bound ? json(*p99_bound) : json(nullptr);
  return out;
}

// A Prometheus counter read back from the server's /metrics (0 where it was never counted).
double counter_from_metrics(const std::string& text, const std::string& name) {
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind(name + ' ', 0) == 0) return std::stod(line.substr(name.size() + 1));
  }
  return 0.0;
}

}  // namespace

json run_serve_bench(const maps::RoadGraph& graph, const ServeBenchConfig& c) {
  if (c.vehicles < 1 || c.missions < 0 || c.missions > c.vehicles || c.seconds <= 0 || c.client_threads < 1 ||
      c.congestion_requests_per_s < 1 || c.repair_threads < 0 || c.repair_threads > 64 || c.rate_per_s < 0 || !std::isfinite(c.rate_per_s)) {
    throw std::invalid_argument("bench serve: need vehicles >= missions >= 0, seconds > 0, threads >= 1, repair threads 0..64, rate >= 0");
  }
  const auto db = std::filesystem::temp_directory_path() / ("corridor-bench-" + std::to_string(::getpid()) + ".db");
  std::filesystem::remove(db);
  server::Store store(db);
  const auto now = [] { return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count(); };
  server::DispatchConfig dispatch;
  dispatch.repair_threads = c.repair_threads > 0 ? c.repair_threads : server::default_repair_threads(c.server_threads);
  dispatch.planner_graph = c.planner_graph;
  dispatch.repair_realtime_priority = c.repair_realtime_priority;
  dispatch.background_nice = c.background_nice;
  server::ServerLimits limits;
  limits.io_nice = c.background_nice;
  server::DispatchService service(graph, dispatch, &store, now());
  server::TokenAuth auth;
  auth.add(kToken, {"bench", server::kAllRoles, std::nullopt});
  server::Router router(service, std::move(auth), {}, now);
  server::HttpServer http(router, service, limits, "127.0.0.1", 0, c.server_threads);
  std::thread server_thread([&] { http.run(); });
  const unsigned short port = http.port();

  // Missions: random origin/destination pairs; each vehicle drives along its route's polyline. The
  // process's resident memory before and after says what the missions' planner state costs.
  const double rss_before_missions = resident_mb();
  std::mt19937_64 rng(c.seed);
  std::vector<std::vector<json>> tracks(static_cast<std::size_t>(c.vehicles));
  {
    Client setup(port);
    // Missions and vehicles on the main component, where every pair of places is joined.
    std::vector<NodeId> main_nodes;
    for (NodeId u : graph.nodes()) {
      if (graph.in_main_component(u)) main_nodes.push_back(u);
    }
    std::uniform_int_distribution<std::size_t> pick(0, main_nodes.size() - 1);
    const auto any_node = [&](std::mt19937_64& r) { return main_nodes[pick(r)]; };
    for (int v = 0; v < c.vehicles; ++v) {
      auto& track = tracks[static_cast<std::size_t>(v)];
      if (v >= c.missions) {
        track.push_back(ll(graph, graph.position(any_node(rng))));
        continue;
      }
      for (int attempt = 0; attempt < 20 && track.empty(); ++attempt) {
        const json body{{"vehicle_id", "v" + std::to_string(v)},
                        {"origin", ll(graph, graph.position(any_node(rng)))},
                        {"destination", ll(graph, graph.position(any_node(rng)))}};
        const auto [status, text] = setup.post("/v1/missions", body.dump());
        if (status != 201) continue;
        const json m = json::parse(text);
        for (const auto& p : m["route"]["geometry"]["coordinates"]) track.push_back({{"lat", p[1]}, {"lon", p[0]}});
      }
      if (track.empty()) throw std::runtime_error("bench serve: could not create mission for vehicle " + std::to_string(v));
    }
  }
  const double rss_with_missions = resident_mb();

  // Load: one keep-alive connection per vehicle plus one sensor connection, all driven by
  // asynchronous I/O on a few client threads, so the load generator spends its share of the cores
  // on requests rather than on thread switches.
  net::io_context client_ioc;
  std::vector<std::unique_ptr<LoadConnection>> vehicles;
  const auto started = Clock::now();
  const auto deadline = started + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(c.seconds));
  const double per_vehicle_period_s = c.rate_per_s > 0 ? static_cast<double>(c.vehicles) / c.rate_per_s : 0.0;
  for (int v = 0; v < c.vehicles; ++v) {
    const auto& track = tracks[static_cast<std::size_t>(v)];
    // Advance one route vertex every 20 reports and stop at 70 % of the route, so every mission
    // stays active for the whole run (a finished mission's positions cost nothing to plan).
    const std::size_t last = track.size() > 3 ? track.size() * 7 / 10 : 0;
    const std::string target = "/v1/vehicles/v" + std::to_string(v) + "/position";
    auto next_body = [&track, last, step = std::size_t{0}]() mutable {
      const json& p = track[std::min(step / 20, last)];
      std::string body = fmt::format(R"({{"lat":{},"lon":{},"timestamp":{},"source":"gps"}})", p["lat"].get<double>(),
                                     p["lon"].get<double>(), step);
      ++step;
      return body;
    };
    // Spread the vehicles' first reports over one period so that a paced load arrives evenly.
    const auto phase = std::chrono::duration<double>(per_vehicle_period_s * v / c.vehicles);
    vehicles.push_back(std::make_unique<LoadConnection>(client_ioc, port, target, std::move(next_body),
                                                        per_vehicle_period_s, deadline,
                                                        started + std::chrono::duration_cast<Clock::duration>(phase)));
  }
  std::mt19937_64 sensor_rng(c.seed + 1);
  std::uniform_int_distribution<std::uint32_t> any_edge(0, static_cast<std::uint32_t>(graph.edge_count() - 1));
  std::uniform_real_distribution<double> factor(1.0, 4.0);
  const auto per_request = static_cast<int>(c.congestion_edges_per_s / c.congestion_requests_per_s);
  LoadConnection sensor(
      client_ioc, port, "/v1/congestion",
      [&] {
        json updates = json::array();
        for (int i = 0; i < per_request; ++i) {
          updates.push_back({{"edge", any_edge(sensor_rng)}, {"factor", factor(sensor_rng)}, {"expires_in_s", 30}});
        }
        return json{{"updates", updates}}.dump();
      },
      1.0 / c.congestion_requests_per_s, deadline, started);
  std::vector<double> replan_latency_ms;  // per congestion request: until its last mission is repaired
  std::vector<double> slowest_replan_ms;  // per congestion request: its slowest single mission repair
  std::vector<double> customization_ms;   // per congestion request: the hierarchy's customization
  sensor.on_body([&](const std::string& body) {
    const json answer = json::parse(body);
    replan_latency_ms.push_back(answer.value("replan_latency_ms", 0.0));
    slowest_replan_ms.push_back(answer.value("slowest_replan_ms", 0.0));
    customization_ms.push_back(answer.value("customization_ms", 0.0));
  });
  for (auto& v : vehicles) v->start();
  if (per_request > 0) sensor.start();
  std::vector<std::thread> clients;
  for (int t = 0; t < c.client_threads; ++t) clients.emplace_back([&] { client_ioc.run(); });
  for (auto& t : clients) t.join();
  const double elapsed = std::chrono::duration<double>(Clock::now() - started).count();
  std::uint64_t errors = sensor.errors();
  std::vector<double> all;
  std::vector<double> send_lags;
  std::vector<double> after_send;
  for (const auto& v : vehicles) {
    all.insert(all.end(), v->latencies_ms().begin(), v->latencies_ms().end());
    send_lags.insert(send_lags.end(), v->send_lags_ms().begin(), v->send_lags_ms().end());
    after_send.insert(after_send.end(), v->after_send_ms().begin(), v->after_send_ms().end());
    errors += v->errors();
  }
  const std::vector<double>& congestion_ms = sensor.latencies_ms();

  const auto commits = service.commit_stats();
  const auto [metrics_status, metrics_text] = Client(port).get("/metrics");
  http.stop();
  server_thread.join();
  std::filesystem::remove(db);
  std::filesystem::remove(db.string() + "-wal");
  std::filesystem::remove(db.string() + "-shm");
  std::filesystem::remove(db.string() + ".lock");

  json out;
  out["graph"] = {{"nodes", graph.node_count()}, {"edges", graph.edge_count()}};
  out["planner_graph"] = service.planner_graph() == server::PlannerGraph::hierarchy ? "hierarchy" : "turn_graph";
  if (const auto* h = service.hierarchy()) {
    out["hierarchy"] = {{"arcs", h->topology().arc_count()}, {"arcs_per_vertex", h->density()}, {"shared_bytes", h->memory_bytes()}};
  }
  out["config"] = {{"vehicles", c.vehicles}, {"missions", c.missions}, {"congestion_edges_per_s", c.congestion_edges_per_s},
                   {"seconds", c.seconds}, {"rate_per_s", c.rate_per_s}, {"client_threads", c.client_threads}, {"server_threads", c.server_threads},
                   {"repair_threads", dispatch.repair_threads}, {"repair_priority", c.repair_realtime_priority},
                   {"background_nice", c.background_nice}};
  // Whether the real-time priority asked for was granted (null: not asked).
  const auto granted = service.repair_realtime_granted();
  out["config"]["repair_priority_granted"] = granted ? json(*granted) : json(nullptr);
  // In-process server and load generator: the resident set is both, the mission delta the server's.
  out["memory"] = {{"rss_mb_before_missions", rss_before_missions},
                   {"rss_mb_with_missions", rss_with_missions},
                   {"rss_mb_at_end", resident_mb()},
                   {"bytes_per_mission", c.missions > 0 ? (rss_with_missions - rss_before_missions) * 1048576.0 / c.missions : 0.0}};
  out["positions"] = latency_json(all);
  out["positions"]["per_s"] = static_cast<double>(all.size()) / elapsed;
  // Paced runs only: how late the load generator itself sent, on the cores it shares with the server.
  if (c.rate_per_s > 0) {
    out["positions"]["send_lag_ms"] = latency_json(send_lags);
    out["positions"]["after_send_ms"] = latency_json(after_send);
  }
  out["congestion"] = latency_json(congestion_ms);
  // Server side, per request: from its arrival to the last mission's repaired route.
  out["congestion"]["replan_latency_ms"] = latency_json(replan_latency_ms);
  out["congestion"]["slowest_mission_replan_ms"] = latency_json(slowest_replan_ms);
  // On the hierarchy, per request: customizing the shared metric, once for all missions, before
  // their repairs (not part of mission_replans).
  out["congestion"]["customization_ms"] = latency_json(customization_ms);
  // Every single mission repair the congestion caused, from the server's own histogram.
  out["congestion"]["mission_replans"] =
      histogram_from_metrics(metrics_status == 200 ? metrics_text : "", "corridor_congestion_mission_replan_seconds");
  // Missions a position report had already repaired when their batch reached them: not sampled.
  out["congestion"]["mission_replans"]["repaired_by_reports"] = static_cast<std::uint64_t>(
      counter_from_metrics(metrics_status == 200 ? metrics_text : "", "corridor_congestion_missions_repaired_by_reports_total"));
  // The same repairs in their thread's CPU time: what the repair costs, without waiting for a core.
  out["congestion"]["mission_replans_cpu"] =
      histogram_from_metrics(metrics_status == 200 ? metrics_text : "", "corridor_congestion_mission_replan_cpu_seconds");
  // From the request's handling to its answer (its commit included), without the time it spent
  // in socket buffers or waiting for an I/O thread: what is the server's own, and what is queueing.
  out["positions"]["server_side"] =
      histogram_from_metrics(metrics_status == 200 ? metrics_text : "", "corridor_http_request_duration_seconds",
                             "route=\"POST /v1/vehicles/{id}/position\"");
  out["congestion"]["edges_per_s"] = static_cast<double>(congestion_ms.size()) *
                                     (c.congestion_edges_per_s / c.congestion_requests_per_s) / elapsed;
  out["errors"] = errors;
  out["active_missions_at_end"] = service.active_mission_count();
  if (commits) {
    // Group commit: how many acknowledged writes shared each SQLite transaction.
    out["commits"] = {{"transactions", commits->commits},
                      {"writes", commits->writes},
                      {"writes_per_transaction", commits->commits > 0 ? static_cast<double>(commits->writes) / commits->commits : 0.0},
                      {"largest", commits->largest_batch}};
  }
  out["note"] = "client-side latency over loopback; clients and server share the machine's cores";
  return out;
}

}  // namespace corridor::bench
