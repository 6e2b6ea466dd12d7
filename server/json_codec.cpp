#include "server/json_codec.hpp"

#include <cmath>

#include "maps/geo.hpp"
#include "planner/route_geojson.hpp"
#include "server/api_error.hpp"

namespace corridor::server {
namespace {

using nlohmann::json;

const json& require(const json& j, const char* key) {
  if (!j.is_object()) throw bad_request("request body must be a JSON object");
  auto it = j.find(key);
  if (it == j.end() || it->is_null()) throw bad_request(std::string("missing field '") + key + "'");
  return *it;
}

double number(const json& v, const char* key) {
  if (!v.is_number()) throw bad_request(std::string("field '") + key + "' must be a number");
  const double d = v.get<double>();
  if (!std::isfinite(d)) throw bad_request(std::string("field '") + key + "' must be finite");
  return d;
}

std::optional<double> optional_number(const json& j, const char* key) {
  auto it = j.find(key);
  if (it == j.end() || it->is_null()) return std::nullopt;
  return number(*it, key);
}

std::string string_field(const json& j, const char* key) {
  const json& v = require(j, key);
  if (!v.is_string()) throw bad_request(std::string("field '") + key + "' must be a string");
  return v.get<std::string>();
}

maps::LatLon lat_lon(const json& v, const char* key) {
  if (!v.is_object()) throw bad_request(std::string("field '") + key + "' must be an object {lat, lon}");
  const maps::LatLon p{number(require(v, "lat"), "lat"), number(require(v, "lon"), "lon")};
  if (!maps::is_valid_lat_lon(p)) {
    throw unprocessable("invalid_coordinate", std::string("field '") + key +
                                                  "' is not a coordinate: lat must be within [-90, 90], lon within [-180, 180]");
  }
  return p;
}

maps::Compass compass(const std::string& s) {
  if (s == "N") return maps::Compass::north;
  if (s == "E") return maps::Compass::east;
  if (s == "S") return maps::Compass::south;
  if (s == "W") return maps::Compass::west;
  throw bad_request("approach must be one of \"N\", \"E\", \"S\", \"W\"");
}

json ll(maps::LatLon p) { return {{"lat", p.lat_deg}, {"lon", p.lon_deg}}; }

}  // namespace

json parse_body(const std::string& body) {
  if (body.empty()) throw bad_request("request body is empty; expected JSON");
  json j = json::parse(body, nullptr, false);
  if (j.is_discarded()) throw bad_request("request body is not valid JSON");
  return j;
}

MissionRequest mission_request_from_json(const json& j) {
  MissionRequest r;
  r.vehicle_id = string_field(j, "vehicle_id");
  r.destination = lat_lon(require(j, "destination"), "destination");
  if (auto it = j.find("origin"); it != j.end() && !it->is_null()) r.origin = lat_lon(*it, "origin");
  if (auto it = j.find("priority"); it != j.end()) {
    if (!it->is_number_integer() || it->get<std::int64_t>() < 0 || it->get<std::int64_t>() > 10) {
      throw bad_request("field 'priority' must be an integer from 0 to 10");
    }
    r.priority = static_cast<int>(it->get<std::int64_t>());
  }
  if (auto it = j.find("profile"); it != j.end()) {
    // Built-in names only: a client does not get to name files on the server.
    if (!it->is_string() || (*it != "ambulance" && *it != "fire_engine")) {
      throw bad_request("field 'profile' must be \"ambulance\" or \"fire_engine\"");
    }
    r.profile = it->get<std::string>();
    // Rounded to the micro-km/h: 120 / 3.6 * 3.6 is not exactly 120 in binary.
    r.vmax_kmh = std::round(planner::builtin_profile(r.profile).vmax_mps * 3.6 * 1e6) / 1e6;
  }
  if (auto v = optional_number(j, "vmax_kmh")) r.vmax_kmh = *v;
  return r;
}

PositionReport position_from_json(const json& j, const std::string& vehicle_id) {
  PositionReport p;
  p.vehicle_id = vehicle_id;
  p.position = {number(require(j, "lat"), "lat"), number(require(j, "lon"), "lon")};
  if (!maps::is_valid_lat_lon(p.position)) {
    throw unprocessable("invalid_coordinate", "lat must be within [-90, 90] and lon within [-180, 180]");
  }
  p.timestamp_s = number(require(j, "timestamp"), "timestamp");
  p.heading_deg = optional_number(j, "heading_deg");
  p.speed_mps = optional_number(j, "speed_mps");
  p.hdop = optional_number(j, "hdop");
  if (auto it = j.find("source"); it != j.end()) {
    if (!it->is_string()) throw bad_request("field 'source' must be \"gps\" or \"vo\"");
    p.source = it->get<std::string>();
  }
  return p;
}

std::vector<CongestionUpdate> congestion_from_json(const json& j) {
  const json& list = require(j, "updates");
  if (!list.is_array()) throw bad_request("field 'updates' must be an array");
  std::vector<CongestionUpdate> out;
  for (const json& u : list) {
    if (!u.is_object()) throw bad_request("each update must be an object");
    CongestionUpdate c;
    if (auto it = u.find("edge"); it != u.end()) {
      if (!it->is_number_unsigned() || it->get<std::uint64_t>() >= 0xffffffffULL) {
        throw bad_request("field 'edge' must be a non-negative integer edge id");
      }
      c.edge = EdgeId{static_cast<std::uint32_t>(it->get<std::uint64_t>())};
    }
    if (auto it = u.find("osm_way_id"); it != u.end()) {
      if (!it->is_number_integer()) throw bad_request("field 'osm_way_id' must be an integer");
      c.osm_way_id = it->get<std::int64_t>();
    }
    c.speed_kmh = optional_number(u, "speed_kmh");
    c.travel_time_s = optional_number(u, "travel_time_s");
    c.factor = optional_number(u, "factor");
    c.expires_in_s = optional_number(u, "expires_in_s");
    out.push_back(c);
  }
  return out;
}

CountsReport counts_from_json(const json& j) {
  CountsReport c;
  c.approach = compass(string_field(j, "approach"));
  c.arrivals = optional_number(j, "arrivals");
  c.departures = optional_number(j, "departures");
  c.occupancy = optional_number(j, "occupancy");
  c.speed_ratio = optional_number(j, "speed_ratio");
  c.queue_m = optional_number(j, "queue_m");
  if (c.arrivals.has_value() != c.departures.has_value()) throw bad_request("fields 'arrivals' and 'departures' go together");
  if (!c.arrivals && !c.occupancy && !c.speed_ratio && !c.queue_m) {
    throw bad_request("give arrivals and departures, occupancy, speed_ratio or queue_m");
  }
  return c;
}

json schedule_to_json(const maps::RoadGraph& graph, const std::vector<preemption::ScheduleEntry>& schedule) {
  json out = json::array();
  for (const auto& e : schedule) {
    const maps::LatLon at = graph.projection().to_lat_lon(graph.position(e.node));
    out.push_back({{"signal", e.node.v},
                   {"osm_node", graph.osm_node(e.node).v},
                   {"location", ll(at)},
                   {"movement", e.movement_label},
                   {"phase", e.phase.label},
                   {"congestion", e.congestion == preemption::CongestionLevel::high ? "high" : "low"},
                   {"start_s", e.start_s},
                   {"arrival_s", e.arrival_s},
                   {"release_s", e.release_s},
                   {"state", preemption::to_string(e.state)},
                   {"deferred", e.deferred}});
  }
  return out;
}

json mission_to_json(const maps::RoadGraph& graph, const MissionView& m) {
  json j{{"id", m.id},
         {"vehicle_id", m.vehicle_id},
         {"state", to_string(m.state)},
         {"priority", m.priority},
         {"vmax_kmh", m.vmax_kmh},
         {"profile", m.profile},
         {"destination", ll(m.destination)},
         {"route_revision", m.route_revision},
         {"created_s", m.created_s},
         {"updated_s", m.updated_s},
         {"preemption", schedule_to_json(graph, m.schedule)}};
  j["last_position"] = m.last_position ? ll(*m.last_position) : json(nullptr);
  if (!m.route.edges.empty()) {
    j["route"] = planner::route_to_geojson(graph, m.route, "dstar", m.congestion_factors.empty() ? nullptr : &m.congestion_factors);
    j["eta_s"] = m.route.found ? json(m.route.travel_time_s) : json(nullptr);
    // Absolute, so a console counts down without knowing when the route was read.
    j["eta_at_s"] = m.route.found && m.state == MissionState::active ? json(m.route_time_s + m.route.travel_time_s) : json(nullptr);
  } else {
    j["route"] = nullptr;
    j["eta_s"] = nullptr;
    j["eta_at_s"] = nullptr;
  }
  return j;
}

json event_to_json(const DispatchEvent& e) {
  json j{{"type", e.kind}, {"time_s", e.time_s}, {"reason", e.reason}, {"seq", e.seq}};
  j["mission"] = e.mission == 0 ? json(nullptr) : json(e.mission);
  if (!e.vehicle_id.empty()) j["vehicle_id"] = e.vehicle_id;
  if (e.position) {
    j["lat"] = e.position->lat_deg;
    j["lon"] = e.position->lon_deg;
    j["heading_deg"] = e.heading_deg ? json(*e.heading_deg) : json(nullptr);
    j["speed_mps"] = e.speed_mps ? json(*e.speed_mps) : json(nullptr);
  }
  if (!e.source.empty()) j["source"] = e.source;
  if (e.eta_s) j["eta_s"] = std::isfinite(*e.eta_s) ? json(*e.eta_s) : json(nullptr);
  if (e.revision) j["revision"] = *e.revision;
  if (e.signal) j["signal"] = e.signal->v;
  if (!e.state.empty()) j["state"] = e.state;
  if (e.edges_changed) j["edges_changed"] = *e.edges_changed;
  if (!e.link.empty()) j["link"] = e.link;
  if (!e.preempt_state.empty()) j["preempt_state"] = e.preempt_state;
  if (e.call_on) j["call_on"] = *e.call_on;
  return j;
}

json vehicle_to_json(const VehicleView& v) {
  json j{{"vehicle_id", v.vehicle_id}, {"lat", v.position.lat_deg}, {"lon", v.position.lon_deg},
         {"timestamp", v.timestamp_s}, {"source", v.source}};
  j["heading_deg"] = v.heading_deg ? json(*v.heading_deg) : json(nullptr);
  j["speed_mps"] = v.speed_mps ? json(*v.speed_mps) : json(nullptr);
  j["mission"] = v.mission ? json(*v.mission) : json(nullptr);
  return j;
}

json revision_to_json(const RouteRevisionView& r) {
  json geometry = json::parse(r.geometry_json, nullptr, false);
  if (geometry.is_discarded()) geometry = nullptr;
  json j{{"revision", r.revision}, {"reason", r.reason}, {"time_s", r.time_s}, {"length_m", r.length_m},
         {"geometry", std::move(geometry)}};
  j["eta_s"] = std::isfinite(r.eta_s) ? json(r.eta_s) : json(nullptr);
  return j;
}

json error_json(const std::string& code, const std::string& message) {
  return {{"error", {{"code", code}, {"message", message}}}};
}

}  // namespace corridor::server
