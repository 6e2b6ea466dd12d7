#include "server/demo_driver.hpp"

#include <spdlog/spdlog.h>

#include <cmath>
#include <numbers>

#include "planner/route.hpp"

namespace corridor::server {
namespace {

bool is_demo(const std::string& vehicle, const std::string& prefix) { return vehicle.rfind(prefix, 0) == 0; }

// The point `along_m` down a polyline, and the compass bearing there.
std::pair<maps::Point2, double> walk(const std::vector<maps::Point2>& line, double along_m) {
  for (std::size_t i = 1; i < line.size(); ++i) {
    const double piece = maps::distance_m(line[i - 1], line[i]);
    if (along_m <= piece || i + 1 == line.size()) {
      const double t = piece > 0.0 ? std::clamp(along_m / piece, 0.0, 1.0) : 0.0;
      const maps::Point2 p{line[i - 1].x_m + t * (line[i].x_m - line[i - 1].x_m),
                           line[i - 1].y_m + t * (line[i].y_m - line[i - 1].y_m)};
      double bearing = std::atan2(line[i].x_m - line[i - 1].x_m, line[i].y_m - line[i - 1].y_m) * 180.0 / std::numbers::pi;
      if (bearing < 0.0) bearing += 360.0;
      return {p, bearing};
    }
    along_m -= piece;
  }
  return {line.back(), 0.0};
}

}  // namespace

DemoDriver::DemoDriver(DispatchService& service, DemoConfig config)
    : service_(service), config_(std::move(config)), rng_(config_.seed) {}

void DemoDriver::step(double now_s, double dt_s) {
  if (next_congestion_s_ == 0.0) next_congestion_s_ = now_s + config_.congestion_period_s;
  top_up(now_s);
  for (const MissionView& m : service_.missions(MissionState::active)) {
    if (is_demo(m.vehicle_id, config_.vehicle_prefix)) drive(m, now_s, dt_s);
  }
  if (now_s >= next_congestion_s_) {
    congest(now_s);
    next_congestion_s_ = now_s + config_.congestion_period_s;
  }
}

void DemoDriver::top_up(double now_s) {
  int active = 0;
  for (const MissionView& m : service_.missions(MissionState::active)) active += is_demo(m.vehicle_id, config_.vehicle_prefix) ? 1 : 0;
  const auto& g = service_.graph();
  std::uniform_int_distribution<std::uint32_t> node(0, static_cast<std::uint32_t>(g.node_count() - 1));
  for (int tries = 0; active < config_.missions && tries < 20; ++tries) {
    const NodeId a{node(rng_)}, b{node(rng_)};
    if (maps::distance_m(g.position(a), g.position(b)) < config_.min_trip_m) continue;
    MissionRequest r;
    r.vehicle_id = config_.vehicle_prefix + std::to_string(next_vehicle_++);
    r.origin = g.projection().to_lat_lon(g.position(a));
    r.destination = g.projection().to_lat_lon(g.position(b));
    r.priority = std::uniform_int_distribution<int>(1, 3)(rng_);
    r.vmax_kmh = 90.0;
    try {
      service_.create_mission(r, now_s);
      ++active;
      spdlog::info("event=demo_mission vehicle={}", r.vehicle_id);
    } catch (const std::exception& e) {
      spdlog::debug("event=demo_mission_skipped reason=\"{}\"", e.what());
    }
  }
}

void DemoDriver::drive(const MissionView& m, double now_s, double dt_s) {
  if (!m.route.found || m.route.edges.empty()) return;
  const auto& g = service_.graph();
  // The plan's own pace: its length over its travel time (signal and congestion delays included),
  // never slower than a crawl, with noise.
  const double planned_mps = m.route.travel_time_s > 0.0 ? m.route.length_m / m.route.travel_time_s : 10.0;
  std::uniform_real_distribution<double> noise(1.0 - config_.speed_noise, 1.0 + config_.speed_noise);
  const double speed = std::max(2.0, planned_mps * noise(rng_));
  const auto line = planner::route_polyline(g, m.route);
  if (line.size() < 2) return;
  const auto [p, bearing] = walk(line, speed * dt_s);
  PositionReport r;
  r.vehicle_id = m.vehicle_id;
  r.position = g.projection().to_lat_lon(p);
  r.heading_deg = bearing;
  r.speed_mps = speed;
  r.timestamp_s = now_s;
  r.source = "gps";
  try {
    const PositionResult res = service_.report_position(r, now_s);
    if (res.durable) res.durable->wait();
    ++positions_sent_;
  } catch (const std::exception& e) {
    spdlog::warn("event=demo_position_failed vehicle={} reason=\"{}\"", m.vehicle_id, e.what());
  }
}

void DemoDriver::congest(double now_s) {
  std::vector<MissionView> demo;
  for (MissionView& m : service_.missions(MissionState::active)) {
    if (is_demo(m.vehicle_id, config_.vehicle_prefix) && m.route.edges.size() > 3) demo.push_back(std::move(m));
  }
  if (demo.empty()) return;
  const MissionView& m = demo[std::uniform_int_distribution<std::size_t>(0, demo.size() - 1)(rng_)];
  // An edge well ahead of the vehicle, so the planner has room to go around it.
  const std::size_t i = std::uniform_int_distribution<std::size_t>(m.route.edges.size() / 3, m.route.edges.size() - 2)(rng_);
  CongestionUpdate u;
  u.edge = m.route.edges[i];
  u.factor = config_.congestion_factor;
  u.expires_in_s = config_.congestion_expiry_s;
  try {
    service_.report_congestion({u}, now_s);
    spdlog::info("event=demo_congestion edge={} mission={}", u.edge->v, m.id);
  } catch (const std::exception& e) {
    spdlog::warn("event=demo_congestion_failed reason=\"{}\"", e.what());
  }
}

}  // namespace corridor::server
