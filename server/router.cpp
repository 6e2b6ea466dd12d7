#include "server/router.hpp"

#include <fmt/format.h>

#include <spdlog/spdlog.h>

#include <chrono>
#include <future>

#include "maps/errors.hpp"
#include "server/json_codec.hpp"
#include "server/openapi_schemas.hpp"

namespace corridor::server {
namespace {

using nlohmann::json;

constexpr std::uint8_t kRead = static_cast<std::uint8_t>(Role::viewer) | static_cast<std::uint8_t>(Role::dispatcher);
constexpr std::uint8_t kDispatch = static_cast<std::uint8_t>(Role::dispatcher);
constexpr std::uint8_t kSensor = static_cast<std::uint8_t>(Role::sensor);
constexpr std::uint8_t kVehicle = static_cast<std::uint8_t>(Role::vehicle);
// Routes that wait for their writes to be durable, or plan whole routes, before they answer.
constexpr bool kBlocking = true;

std::vector<std::string> split_path(std::string_view path) {
  std::vector<std::string> parts;
  std::size_t begin = 0;
  while (begin <= path.size()) {
    const std::size_t end = std::min(path.find('/', begin), path.size());
    if (end > begin) parts.emplace_back(path.substr(begin, end - begin));
    begin = end + 1;
  }
  return parts;
}

std::uint64_t parse_id(const std::string& s, const char* what) {
  if (s.empty() || s.size() > 18 || s.find_first_not_of("0123456789") != std::string::npos) {
    throw bad_request(std::string(what) + " must be a positive integer, got '" + s.substr(0, 40) + "'");
  }
  return std::stoull(s);
}

json map_feature_collection(const maps::RoadGraph& g) {
  json features = json::array();
  for (EdgeId e : g.edges()) {
    if (g.twin(e).valid() && g.twin(e) < e) continue;  // one feature per road
    json coords = json::array();
    for (const auto& p : g.geometry(e)) {
      const maps::LatLon ll = g.projection().to_lat_lon(p);
      coords.push_back({std::round(ll.lon_deg * 1e7) / 1e7, std::round(ll.lat_deg * 1e7) / 1e7});
    }
    features.push_back({{"type", "Feature"},
                        {"geometry", {{"type", "LineString"}, {"coordinates", std::move(coords)}}},
                        {"properties",
                         {{"edge", e.v},
                          {"twin", g.twin(e).valid() ? json(g.twin(e).v) : json(nullptr)},
                          {"osm_way_id", g.osm_way(e).v},
                          {"class", std::string(maps::to_string(g.road_class(e)))},
                          {"speed_kmh", g.speed_mps(e) * 3.6},
                          {"length_m", g.length_m(e)},
                          {"name", g.name(e)},
                          {"ref", g.ref(e)}}}});
  }
  const maps::LatLon lo = g.projection().to_lat_lon(g.min_corner());
  const maps::LatLon hi = g.projection().to_lat_lon(g.max_corner());
  return {{"type", "FeatureCollection"},
          {"features", std::move(features)},
          {"bounds", {{lo.lon_deg, lo.lat_deg}, {hi.lon_deg, hi.lat_deg}}},
          {"attribution", "© OpenStreetMap contributors, ODbL 1.0"}};
}

json roles_json(std::uint8_t roles) {
  json out = json::array();
  for (auto [role, name] : {std::pair{Role::dispatcher, "dispatcher"}, std::pair{Role::vehicle, "vehicle"},
                            std::pair{Role::sensor, "sensor"}, std::pair{Role::viewer, "viewer"}}) {
    if ((roles & static_cast<std::uint8_t>(role)) != 0) out.push_back(name);
  }
  return out;
}

// A path segment or query value with its %XX escapes decoded (RFC 3986; '+' stays '+'), so that a
// vehicle id such as "unit 7", sent as "unit%207", names the same vehicle as in the mission's JSON.
std::string percent_decoded(std::string_view in) {
  const auto hex = [](char c) -> int {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
  };
  std::string out;
  out.reserve(in.size());
  for (std::size_t i = 0; i < in.size(); ++i) {
    if (in[i] != '%') {
      out.push_back(in[i]);
      continue;
    }
    const int hi = i + 2 < in.size() ? hex(in[i + 1]) : -1;
    const int lo = hi >= 0 ? hex(in[i + 2]) : -1;
    if (lo < 0) throw bad_request("malformed percent-encoding in '" + std::string(in.substr(0, 40)) + "'");
    out.push_back(static_cast<char>(hi * 16 + lo));
    i += 2;
  }
  return out;
}

// The query of a target ("/v1/x?a=1&b"): {a: "1", b: ""}; a key given twice keeps its last value.
std::unordered_map<std::string, std::string> parse_query(const std::string& target) {
  std::unordered_map<std::string, std::string> query;
  const auto q = target.find('?');
  if (q == std::string::npos) return query;
  for (std::size_t begin = q + 1; begin <= target.size();) {
    const std::size_t end = std::min(target.find('&', begin), target.size());
    const std::string_view pair(target.data() + begin, end - begin);
    if (!pair.empty()) {
      const auto eq = pair.find('=');
      query[percent_decoded(pair.substr(0, eq))] = eq == std::string_view::npos ? "" : percent_decoded(pair.substr(eq + 1));
    }
    begin = end + 1;
  }
  return query;
}

}  // namespace

Router::Router(DispatchService& service, TokenAuth auth, RouterConfig config, Clock clock,
               std::shared_ptr<const StaticSite> site)
    : service_(service), auth_(std::move(auth)), config_(config), clock_(std::move(clock)), site_(std::move(site)) {
  map_geojson_ = map_feature_collection(service_.graph()).dump();
  subscription_ = service_.subscribe([this](const DispatchEvent& e) {
    if (e.kind == "route_changed") metrics_.count("route_changes_total");
    if (e.kind.rfind("preemption_", 0) == 0) metrics_.count(e.kind + "_total");
  });

  add("GET", "/v1/health", 0, "Liveness, map size and active missions", [this](const Principal&, const Match&, const HttpRequest&) {
    return json_response(200, {{"status", "ok"},
                               {"active_missions", service_.active_mission_count()},
                               {"map", {{"nodes", service_.graph().node_count()}, {"edges", service_.graph().edge_count()}}}});
  });
  add("GET", "/metrics", 0, "Prometheus metrics", [this](const Principal&, const Match&, const HttpRequest&) {
    metrics_.set_gauge("active_missions", static_cast<double>(service_.active_mission_count()));
    return HttpResponse{200, "text/plain; version=0.0.4", metrics_.render(), nullptr, {}};
  });
  add("GET", "/v1/openapi.json", 0, "This API description", [this](const Principal&, const Match&, const HttpRequest&) {
    return json_response(200, openapi());
  });
  add("GET", "/v1/me", kAllRoles, "The calling token's name and roles", [](const Principal& who, const Match&, const HttpRequest&) {
    json out{{"name", who.name}, {"roles", roles_json(who.roles)}};
    out["vehicle_id"] = who.vehicle_id ? json(*who.vehicle_id) : json(nullptr);
    return HttpResponse{200, "application/json", out.dump(), nullptr, {}};
  });
  add("POST", "/v1/stream/ticket", kRead, "A single-use ticket to open the WebSocket stream (?ticket=) within 30 s",
      [this](const Principal& who, const Match&, const HttpRequest&) {
        return json_response(200, {{"ticket", tickets_.issue(who, clock_())}, {"expires_in_s", tickets_.config().lifetime_s}});
      });
  add("GET", "/v1/vehicles", kRead, "Every vehicle's latest accepted position", [this](const Principal&, const Match&, const HttpRequest&) {
    json list = json::array();
    for (const auto& v : service_.vehicles()) list.push_back(vehicle_to_json(v));
    return json_response(200, {{"vehicles", std::move(list)}});
  });
  add("GET", "/v1/missions/{id}/routes", kRead, "A mission's route revisions with their reasons, oldest first",
      [this](const Principal&, const Match& m, const HttpRequest&) {
        json list = json::array();
        for (const auto& r : service_.route_history(parse_id(m.params[0], "mission id"))) list.push_back(revision_to_json(r));
        return json_response(200, {{"revisions", std::move(list)}});
      });
  add("GET", "/v1/map", kRead, "The road graph as GeoJSON", [this](const Principal&, const Match&, const HttpRequest&) {
    return HttpResponse{200, "application/geo+json", map_geojson_, nullptr, {}};
  });
  add("POST", "/v1/missions", kDispatch, "Create a mission", [this](const Principal&, const Match&, const HttpRequest& r) {
    const auto started = std::chrono::steady_clock::now();
    const MissionView m = service_.create_mission(mission_request_from_json(parse_body(r.body)), clock_());
    metrics_.observe("plan_seconds", std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count());
    return json_response(201, mission_to_json(service_.graph(), m));
  }, kBlocking);
  add("GET", "/v1/missions", kRead, "List missions (?state=active|completed|cancelled)",
      [this](const Principal&, const Match& m, const HttpRequest&) {
        std::optional<MissionState> state;
        if (auto it = m.query.find("state"); it != m.query.end()) {
          state = mission_state_from(it->second);
          if (!state) throw bad_request("state must be active, completed or cancelled");
        }
        json list = json::array();
        for (const auto& v : service_.missions(state)) list.push_back(mission_to_json(service_.graph(), v));
        return json_response(200, {{"missions", std::move(list)}});
      });
  add("GET", "/v1/missions/{id}", kRead, "One mission", [this](const Principal&, const Match& m, const HttpRequest&) {
    return json_response(200, mission_to_json(service_.graph(), service_.mission(parse_id(m.params[0], "mission id"))));
  });
  add("POST", "/v1/missions/{id}/cancel", kDispatch, "Cancel a mission",
      [this](const Principal&, const Match& m, const HttpRequest&) {
        return json_response(200, mission_to_json(service_.graph(), service_.cancel_mission(parse_id(m.params[0], "mission id"), clock_())));
      }, kBlocking);
  add("POST", "/v1/vehicles/{id}/position", kVehicle | kDispatch, "Report a vehicle position",
      [this](const Principal& who, const Match& m, const HttpRequest& r) {
        const std::string& vehicle = m.params[0];
        // TokenAuth gives every vehicle token without the dispatcher role its vehicle_id.
        if (!who.has(Role::dispatcher) && who.vehicle_id != vehicle) {
          throw ApiError(403, "forbidden", "this token may report positions for vehicle '" + who.vehicle_id.value_or("") + "' only");
        }
        const auto started = std::chrono::steady_clock::now();
        const PositionReport raw = position_from_json(parse_body(r.body), vehicle);
        const PositionResult res = service_.report_position(raw, clock_());
        metrics_.observe("position_replan_seconds", std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count());
        json out{{"accepted", true},
                 {"followed", res.match.disposition == "followed"},
                 {"disposition", res.match.disposition},
                 {"raw", {{"lat", raw.position.lat_deg}, {"lon", raw.position.lon_deg}, {"timestamp", raw.timestamp_s},
                          {"source", raw.source}}},
                 {"snap_distance_m", res.snap_distance_m},
                 {"route_changed", res.route_changed},
                 {"completed", res.completed}};
        out["mission"] = res.mission ? json(*res.mission) : json(nullptr);
        out["eta_s"] = res.mission && !res.completed ? json(res.eta_s) : json(nullptr);
        if (res.match.edge) {
          const EdgeId e = *res.match.edge;
          out["edge"] = e.v;
          out["osm_way_id"] = service_.graph().osm_way(e).v;
          out["name"] = service_.graph().name(e);
          out["offset_m"] = res.match.offset_m;
          out["match_confidence"] = res.match.confidence;
        } else {
          out["edge"] = nullptr;
          out["match_confidence"] = nullptr;
        }
        HttpResponse response = json_response(200, out);
        response.after_commit = res.durable;
        return response;
      });
  add("POST", "/v1/congestion", kSensor, "Report congestion on edges or OSM ways",
      [this](const Principal&, const Match&, const HttpRequest& r) {
        const auto started = std::chrono::steady_clock::now();
        const CongestionResult res = service_.report_congestion(congestion_from_json(parse_body(r.body)), clock_());
        metrics_.observe("congestion_replan_seconds", std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count());
        metrics_.count("replans_total", static_cast<double>(res.missions_replanned));
        metrics_.count("congestion_missions_repaired_by_reports_total", static_cast<double>(res.missions_repaired_by_reports));
        for (double s : res.mission_replan_s) metrics_.observe("congestion_mission_replan_seconds", s);
        for (double s : res.mission_replan_cpu_s) metrics_.observe("congestion_mission_replan_cpu_seconds", s);
        if (service_.hierarchy() != nullptr) metrics_.observe("congestion_customization_seconds", res.customization_s);
        return json_response(200, {{"edges_changed", res.edges_changed},
                                   {"missions_replanned", res.missions_replanned},
                                   {"missions_repaired_by_reports", res.missions_repaired_by_reports},
                                   {"routes_changed", res.routes_changed},
                                   {"replan_latency_ms", res.replan_latency_s * 1e3},
                                   {"slowest_replan_ms", res.slowest_replan_s * 1e3},
                                   {"customization_ms", res.customization_s * 1e3}});
      }, kBlocking);
  add("POST", "/v1/signals/{id}/counts", kSensor,
      "A signal's detector report for one approach: counts, occupancy or speed ratio, and the standing queue (DetectorReport)",
      [this](const Principal&, const Match& m, const HttpRequest& r) {
        const auto id = parse_id(m.params[0], "signal id");
        if (id >= service_.graph().node_count()) throw not_found("no signal " + m.params[0]);
        const CountsReport c = counts_from_json(parse_body(r.body));
        service_.report_detectors(NodeId{static_cast<std::uint32_t>(id)}, c, clock_());
        return json_response(200, {{"accepted", true}});
      });
  auto signal_json = [this](NodeId n, const maps::SignalPlan& plan) {
    json lights = json::array();
    const auto shown = service_.signal_lights(n);
    for (std::size_t i = 0; i < plan.movements.size(); ++i) {
      const char* light = shown[i] == preemption::Light::green ? "green" : shown[i] == preemption::Light::yellow ? "yellow" : "red";
      lights.push_back({{"movement", plan.movements[i].label()}, {"light", light}});
    }
    const maps::LatLon at = service_.graph().projection().to_lat_lon(service_.graph().position(n));
    json phases = json::array();
    for (const auto& p : plan.phases) phases.push_back(p.label);
    const auto [mode, step] = service_.signal_mode(n);
    json out{{"id", n.v}, {"osm_node", service_.graph().osm_node(n).v}, {"location", {{"lat", at.lat_deg}, {"lon", at.lon_deg}}},
             {"phases", std::move(phases)}, {"lights", std::move(lights)},
             {"mode", mode}, {"program_step", step}, {"state", service_.signal_state(n)}};
    if (const std::string name = service_.signal_name(n); !name.empty()) out["tls_id"] = name;
    if (const auto field = service_.field_status(n)) {
      json f{{"controller", field->controller}, {"link", ntcip::to_string(field->link)}, {"call_on", field->call_on},
             {"lights_reported", !field->lights.empty()}};
      if (field->last_answer_s) f["last_answer_s"] = *field->last_answer_s;
      if (!field->last_error.empty()) f["error"] = field->last_error;
      if (field->preempt != 0) f["preempt"] = field->preempt;
      if (field->preempt_state) f["preempt_state"] = ntcip::to_string(*field->preempt_state);
      f["answers"] = field->answers;
      if (field->rtt_p50_ms) f["rtt_p50_ms"] = *field->rtt_p50_ms;
      if (field->rtt_p99_ms) f["rtt_p99_ms"] = *field->rtt_p99_ms;
      out["field"] = std::move(f);
    }
    return out;
  };
  const auto calls_response = [this](const std::vector<SignalCallRow>& calls, const Match& m) {
    const auto format = m.query.find("format");
    if (format != m.query.end() && format->second == "csv") {
      std::string csv = "id,signal,controller,mission_id,vehicle_id,priority,kind,preempt,approach,request_s,grant_s,release_s,clear_s,outcome\n";
      const auto t = [](std::optional<double> v) { return v ? fmt::format("{:.3f}", *v) : std::string{}; };
      const auto quoted = [](const std::string& v) {
        if (v.find_first_of(",\"\r\n") == std::string::npos) return v;
        std::string q = "\"";
        for (char c : v) q += c == '"' ? std::string("\"\"") : std::string(1, c);
        return q + "\"";
      };
      for (const auto& c : calls) {
        csv += fmt::format("{},{},{},{},{},{},{},{},{},{:.3f},{},{},{},{}\n", c.id, c.signal.v, quoted(c.controller),
                           c.mission ? std::to_string(*c.mission) : std::string{}, quoted(c.vehicle_id), c.priority, c.kind, c.preempt,
                           c.approach, c.request_s, t(c.grant_s), t(c.release_s), t(c.clear_s), c.outcome);
      }
      return HttpResponse{200, "text/csv; charset=utf-8", std::move(csv), nullptr, {}};
    }
    if (format != m.query.end() && format->second != "json") throw bad_request("format must be json or csv");
    json list = json::array();
    for (const auto& c : calls) {
      json j{{"id", c.id}, {"signal", c.signal.v}, {"controller", c.controller}, {"vehicle_id", c.vehicle_id},
             {"missions", c.missions}, {"priority", c.priority}, {"kind", c.kind}, {"approach", c.approach},
             {"request_s", c.request_s}, {"outcome", c.outcome}};
      if (c.mission) j["mission_id"] = *c.mission;
      if (c.kind == "preempt") j["preempt"] = c.preempt;
      if (c.grant_s) j["grant_s"] = *c.grant_s;
      if (c.release_s) j["release_s"] = *c.release_s;
      if (c.clear_s) j["clear_s"] = *c.clear_s;
      list.push_back(std::move(j));
    }
    return json_response(200, {{"calls", std::move(list)}});
  };
  const auto calls_limit = [](const Match& m) {
    const auto it = m.query.find("limit");
    if (it == m.query.end()) return std::size_t{200};
    const auto n = parse_id(it->second, "limit");
    if (n < 1 || n > 10000) throw bad_request("limit must be 1..10000");
    return static_cast<std::size_t>(n);
  };
  add("GET", "/v1/signals/{id}/calls", kRead,
      "Call records of a field-controlled signal, newest first (?limit=N, ?format=csv): request, grant, release, clear, outcome",
      [this, calls_response, calls_limit](const Principal&, const Match& m, const HttpRequest&) {
        const auto id = parse_id(m.params[0], "signal id");
        if (id >= service_.graph().node_count()) throw not_found("no signal " + m.params[0]);
        return calls_response(service_.signal_calls(NodeId{static_cast<std::uint32_t>(id)}, calls_limit(m)), m);
      }, kBlocking);
  add("GET", "/v1/missions/{id}/calls", kRead, "Call records of a mission's signals on field controllers (?limit=N, ?format=csv)",
      [this, calls_response, calls_limit](const Principal&, const Match& m, const HttpRequest&) {
        return calls_response(service_.mission_calls(parse_id(m.params[0], "mission id"), calls_limit(m)), m);
      }, kBlocking);
  add("GET", "/v1/signals", kRead, "Every signalized intersection", [this, signal_json](const Principal&, const Match&, const HttpRequest&) {
    json list = json::array();
    std::vector<NodeId> ids;
    for (const auto& [n, plan] : service_.signal_plans()) ids.push_back(n);
    std::sort(ids.begin(), ids.end());
    for (NodeId n : ids) list.push_back(signal_json(n, service_.signal_plans().at(n)));
    return json_response(200, {{"signals", std::move(list)}});
  });
  add("GET", "/v1/signals/{id}", kRead, "One signalized intersection", [this, signal_json](const Principal&, const Match& m, const HttpRequest&) {
    const auto id = parse_id(m.params[0], "signal id");
    auto it = id < service_.graph().node_count() ? service_.signal_plans().find(NodeId{static_cast<std::uint32_t>(id)})
                                                 : service_.signal_plans().end();
    if (it == service_.signal_plans().end()) throw not_found("no signal " + m.params[0]);
    return json_response(200, signal_json(it->first, it->second));
  });
}

Router::~Router() { service_.unsubscribe(subscription_); }

void Router::add(std::string method, std::string pattern, std::uint8_t roles, std::string summary, Handler handler,
                 bool blocking) {
  auto segments = split_path(pattern);
  routes_.push_back(
      {std::move(method), std::move(pattern), std::move(segments), roles, std::move(summary), std::move(handler), blocking});
}

HttpResponse Router::json_response(int status, const json& body) const {
  return {status, "application/json", body.dump(-1, ' ', false, json::error_handler_t::replace), nullptr, {}};
}

bool Router::take_token(const std::string& key, double now_s) {
  std::lock_guard lock(buckets_mutex_);
  auto [it, fresh] = buckets_.try_emplace(key, config_.burst_per_token, now_s);
  auto& [left, last] = it->second;
  if (!fresh) {
    left = std::min(config_.burst_per_token, left + (now_s - last) * config_.rate_per_token_per_s);
    last = now_s;
  }
  if (left < 1.0) return false;
  left -= 1.0;
  return true;
}

std::optional<Principal> Router::authorize_stream(const std::string& authorization, const std::string& target) {
  std::unordered_map<std::string, std::string> query;
  try {
    query = parse_query(target);
  } catch (const ApiError&) {
    query.clear();  // a malformed query carries no ticket: the Authorization header may still hold
  }
  const auto it = query.find("ticket");
  const std::string ticket = it == query.end() ? std::string() : it->second;
  auto who = ticket.empty() ? auth_.authenticate(authorization) : tickets_.redeem(ticket, clock_());
  if (!who || (who->roles & kRead) == 0) return std::nullopt;
  return who;
}

HttpResponse Router::storage_failure(const std::string& route_name, const std::string& error) const {
  spdlog::error("event=store_failure route=\"{}\" error=\"{}\"", route_name, error);
  return json_response(503, error_json("storage_unavailable", "the change could not be stored; it was not acknowledged"));
}

HttpResponse Router::handle(const HttpRequest& request) noexcept {
  // handle_async always replies exactly once, so the future always gets its value.
  std::promise<HttpResponse> answered;
  auto response = answered.get_future();
  handle_async(request, [&answered](HttpResponse r) { answered.set_value(std::move(r)); });
  return response.get();
}

void Router::handle_async(const HttpRequest& request, std::function<void(HttpResponse)> reply) noexcept {
  const auto started = std::chrono::steady_clock::now();
  std::string route_name = "unmatched";
  HttpResponse response = answer(request, route_name);
  auto finish = [this, started, route_name, reply = std::move(reply)](HttpResponse r) {
    metrics_.observe_request(route_name, r.status,
                             std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count());
    try {
      reply(std::move(r));
    } catch (const std::exception& e) {
      spdlog::error("event=reply_failed route=\"{}\" error=\"{}\"", route_name, e.what());
    }
  };
  if (!response.after_commit) return finish(std::move(response));
  const auto ticket = std::exchange(response.after_commit, nullptr);
  ticket->on_done([this, route_name, response = std::move(response), finish = std::move(finish)](const std::string* error) mutable {
    finish(error != nullptr ? storage_failure(route_name, *error) : std::move(response));
  });
}

const Router::Route* Router::match_route(const std::string& method, std::string_view path, std::vector<std::string>& params,
                                         bool& path_known) const {
  const auto parts = split_path(path);
  for (const Route& r : routes_) {
    const auto& pattern = r.segments;
    if (pattern.size() != parts.size()) continue;
    bool ok = true;
    for (std::size_t i = 0; i < parts.size() && ok; ++i) ok = pattern[i].front() == '{' || pattern[i] == parts[i];
    if (!ok) continue;
    path_known = true;
    if (r.method != method) continue;
    params.clear();
    for (std::size_t i = 0; i < parts.size(); ++i) {
      if (pattern[i].front() == '{') params.push_back(percent_decoded(parts[i]));
    }
    return &r;
  }
  return nullptr;
}

bool Router::blocks(const HttpRequest& request) const noexcept {
  try {
    const std::string_view target(request.target);
    std::vector<std::string> params;
    bool path_known = false;
    const Route* r = match_route(request.method, target.substr(0, target.find('?')), params, path_known);
    return r != nullptr && r->blocking;
  } catch (...) {
    return false;  // a malformed path, or out of memory: answer() will say so
  }
}

HttpResponse Router::answer(const HttpRequest& request, std::string& route_name) noexcept {
  HttpResponse response;
  try {
    const auto q = request.target.find('?');
    const std::string path = request.target.substr(0, q);
    Match match;
    // Outside the API: the console's files (GET and HEAD only), whatever their query holds.
    if (site_ && path.rfind("/v1/", 0) != 0 && path != "/v1" && path != "/metrics") {
      route_name = "GET /";
      if (request.method != "GET" && request.method != "HEAD") {
        throw ApiError(405, "method_not_allowed", request.method + " is not allowed on " + path.substr(0, 200));
      }
      StaticReply r = site_->serve(path);
      if (r.status != 200) throw ApiError(r.status, r.error_code, r.error_message);
      return HttpResponse{200, std::move(r.content_type), std::string(r.body), nullptr, std::move(r.headers)};
    }
    match.query = parse_query(request.target);
    bool path_known = false;
    const Route* found = match_route(request.method, path, match.params, path_known);
    if (found == nullptr) {
      throw path_known ? ApiError(405, "method_not_allowed", request.method + " is not allowed on " + path)
                       : not_found("no such endpoint: " + path.substr(0, 200));
    }
    route_name = found->method + " " + found->pattern;
    Principal who{"anonymous", kAllRoles, std::nullopt};
    if (found->roles != 0) {
      auto principal = auth_.authenticate(request.authorization);
      if (!principal) throw ApiError(401, "unauthorized", "a valid 'Authorization: Bearer <token>' header is required");
      if ((principal->roles & found->roles) == 0) {
        throw ApiError(403, "forbidden", "token '" + principal->name + "' may not call " + route_name);
      }
      if (!take_token(principal->name, clock_())) {
        throw ApiError(429, "rate_limited", "too many requests for token '" + principal->name + "'; slow down");
      }
      who = *principal;
    }
    response = found->handler(who, match, request);
  } catch (const ApiError& e) {
    response = json_response(e.status(), error_json(e.code(), e.what()));
  } catch (const nlohmann::json::exception& e) {
    response = json_response(400, error_json("bad_request", std::string("invalid JSON value: ") + e.what()));
  } catch (const StoreError& e) {
    response = storage_failure(route_name, e.what());
  } catch (const std::exception& e) {
    spdlog::error("event=internal_error route=\"{}\" error=\"{}\"", route_name, e.what());
    response = json_response(500, error_json("internal", "internal error; the request was not applied"));
  } catch (...) {
    response = json_response(500, error_json("internal", "internal error; the request was not applied"));
  }
  return response;
}

json Router::openapi() const {
  json paths = json::object();
  for (const Route& r : routes_) {
    json op{{"summary", r.summary},
            {"responses",
             {{"200", {{"description", "OK"}}},
              {"400", {{"description", "Malformed request"}, {"content", {{"application/json", {{"schema", {{"$ref", "#/components/schemas/Error"}}}}}}}}},
              {"401", {{"description", "Missing or invalid token"}}},
              {"403", {{"description", "Token lacks the role"}}},
              {"404", {{"description", "Unknown id"}}},
              {"422", {{"description", "Valid JSON that cannot be applied (off the map, unreachable)"}}}}}};
    if (r.method == "POST" && r.pattern == "/v1/missions") op["responses"]["201"] = {{"description", "Created"}};
    if (r.roles != 0) op["security"] = json::array({{{"bearer", json::array()}}});
    json params = json::array();
    for (const auto& part : r.segments) {
      if (part.front() == '{') {
        params.push_back({{"name", part.substr(1, part.size() - 2)}, {"in", "path"}, {"required", true}, {"schema", {{"type", "string"}}}});
      }
    }
    if (!params.empty()) op["parameters"] = std::move(params);
    std::string method = r.method;
    std::transform(method.begin(), method.end(), method.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    paths[r.pattern][method] = std::move(op);
  }
  paths["/v1/stream"]["get"] = {{"summary", "WebSocket stream of events (upgrade); ?mission=ID to follow one mission"},
                                {"responses", {{"101", {{"description", "Switching protocols"}}}}},
                                {"security", json::array({{{"bearer", json::array()}}})}};
  json error_schema = {{"type", "object"},
                       {"properties",
                        {{"error",
                          {{"type", "object"},
                           {"properties", {{"code", {{"type", "string"}}}, {"message", {{"type", "string"}}}}}}}}}};
  json schemas = json::parse(openapi_schemas_json());
  if (!schemas.contains("Error")) schemas["Error"] = std::move(error_schema);
  json components = {{"securitySchemes", {{"bearer", {{"type", "http"}, {"scheme", "bearer"}}}}},
                     {"schemas", std::move(schemas)}};
  return {{"openapi", "3.0.3"},
          {"info", {{"title", "Corridor dispatch API"}, {"version", "1"}}},
          {"paths", std::move(paths)},
          {"components", std::move(components)}};
}

}  // namespace corridor::server
