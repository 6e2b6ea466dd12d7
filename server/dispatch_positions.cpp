// The position path: a vehicle's report, matched by its tracker, stored and answered once durable;
// for a vehicle on a mission, its planner's start moved and its route repaired, and the signals
// ahead retimed.
#include <spdlog/spdlog.h>

#include <cmath>

#include "maps/errors.hpp"
#include "maps/text_id.hpp"
#include "planner/snap_points.hpp"
#include "server/dispatch_mission.hpp"
#include "server/dispatch_service.hpp"

namespace corridor::server {
namespace {

DispatchEvent position_event(const PositionReport& p, double now_s, MissionId mission, std::optional<double> eta_s) {
  DispatchEvent e;
  e.kind = "position";
  e.mission = mission;
  e.reason = p.source;
  e.time_s = now_s;
  e.vehicle_id = p.vehicle_id;
  e.position = p.position;
  e.heading_deg = p.heading_deg;
  e.speed_mps = p.speed_mps;
  e.source = p.source;
  e.eta_s = eta_s;
  return e;
}

}  // namespace

PositionResult DispatchService::report_position(const PositionReport& p, double now_s) {
  if (const auto problem = maps::id_problem(p.vehicle_id)) throw bad_request("vehicle id: the id " + *problem);
  if (p.source != "gps" && p.source != "vo") throw bad_request("source must be \"gps\" or \"vo\"");
  if (p.heading_deg && !(std::isfinite(*p.heading_deg) && *p.heading_deg >= 0.0 && *p.heading_deg <= 360.0)) {
    throw bad_request("heading_deg must be within [0, 360]");
  }
  if (p.speed_mps && !(std::isfinite(*p.speed_mps) && *p.speed_mps >= 0.0 && *p.speed_mps < 150.0)) {
    throw bad_request("speed_mps must be within [0, 150)");
  }
  if (p.hdop && !(std::isfinite(*p.hdop) && *p.hdop >= 0.0)) throw bad_request("hdop must be a number >= 0");
  if (!(std::isfinite(p.timestamp_s) && p.timestamp_s >= 0.0)) {
    throw bad_request("timestamp must be a finite number of seconds since the Unix epoch, >= 0");
  }
  // A report from the future would make every later one stale (the tracker keeps the newest time).
  if (p.timestamp_s > now_s + config_.max_clock_ahead_s) {
    throw bad_request(fmt::format("timestamp is {:g} s ahead of the server's clock; at most {:g} s of skew is taken",
                                  p.timestamp_s - now_s, config_.max_clock_ahead_s));
  }
  // Off the map is bad input whatever else the report is: checked before the tracker.
  maps::SnapResult snap;
  try {
    snap = snapper_.snap(p.position, {config_.snap_max_distance_m});
  } catch (const maps::SnapError& e) {
    throw snap_error(e, "position");
  }
  PositionResult result;
  // The tracker first, alone: a stale, duplicate or outlying report, or GPS too poor to follow, is
  // stored as received and moves nothing.
  const TrackResult tracked = tracker_.track(p);
  result.match.disposition = to_string(tracked.disposition);
  if (tracked.disposition != Disposition::followed) {
    Staged staged;
    stage(staged, [p, now_s, match = result.match](Store& store) { store.insert_position(p, std::nullopt, now_s, match); });
    result.durable = submit(staged);
    return result;
  }
  if (tracked.match.matched) {
    // The matcher's point: the road and direction the vehicle's recent fixes say it drives.
    snap.edge = tracked.match.edge;
    snap.offset_m = tracked.match.offset_m;
    snap.point = tracked.match.point;
    snap.distance_m = tracked.match.distance_m;
    result.match.edge = tracked.match.edge;
    result.match.offset_m = tracked.match.offset_m;
    result.match.confidence = tracked.match.confidence;
  }
  result.snap_distance_m = snap.distance_m;
  MissionPtr mp;
  {
    std::lock_guard lock(registry_mutex_);
    VehicleView& v = vehicles_[p.vehicle_id];
    v = {p.vehicle_id, p.position, p.heading_deg, p.speed_mps, p.timestamp_s, p.source, std::nullopt};
    if (auto it = active_by_vehicle_.find(p.vehicle_id); it != active_by_vehicle_.end()) mp = missions_.at(it->second);
  }
  Staged staged;
  std::unique_lock<std::mutex> lock;
  if (mp) {
    lock = std::unique_lock(mp->mutex);
    if (mp->row.state != MissionState::active) mp.reset();  // it ended in between
  }
  if (!mp) {
    stage(staged, [p, now_s, match = result.match](Store& store) { store.insert_position(p, std::nullopt, now_s, match); });
    result.durable = submit(staged);
    emit(position_event(p, now_s, 0, std::nullopt));  // a free vehicle moves on the console too
    return result;
  }
  Mission& m = *mp;
  result.mission = m.row.id;
  stage(staged, [p, id = m.row.id, now_s, match = result.match](Store& store) { store.insert_position(p, id, now_s, match); });
  m.last_position = p.position;

  // Signals behind the vehicle: every intersection of the old route before its current edge. A
  // matched point already knows its direction; a raw snap asks the heading.
  auto points = tracked.match.matched ? std::vector<planner::EdgePoint>{{snap.edge, snap.offset_m}}
                                      : endpoints(snap, Role::start, p.heading_deg);
  // Still on the edge the route started from, or just onto the next one, the vehicle is in the
  // turn-graph state the route drove it in: a via-way restriction it has entered still binds it
  // after the replan. Further along (reports missed, a loop that uses an edge twice, a vehicle that
  // left the route and came back another way) the way it came is not known, and it starts afresh.
  for (planner::EdgePoint& q : points) {
    for (std::size_t i = 0; i < 2 && i < m.route.edges.size(); ++i) {
      if (m.route.edges[i] == q.edge) {
        q.turn_vertex = m.route.point_on(i, 0.0).turn_vertex;
        break;
      }
    }
  }
  const auto pos_in_route = std::find_if(m.route.edges.begin(), m.route.edges.end(), [&](EdgeId e) {
    return std::any_of(points.begin(), points.end(), [&](const planner::EdgePoint& q) { return q.edge == e; });
  });
  if (pos_in_route != m.route.edges.end()) {
    const auto passed = static_cast<std::size_t>(pos_in_route - m.route.edges.begin());
    std::lock_guard signals(preemption_mutex_);
    for (std::size_t i = 0; i < passed && i < m.route.nodes.size(); ++i) {
      if (plans_.count(m.route.nodes[i]) != 0) preemption_.vehicle_passed(m.row.id, signals_map_.key(m.route.nodes[i]), now_s);
    }
  }

  const std::vector<EdgeId> old_edges = m.route.edges;
  // This repair also covers any cost change the planner heard of since its last one.
  const std::string reason = repair(m, &points).value_or("off_route");
  if (!m.route.found) {
    // On a road cut off from the rest (a car park that joins no public road): on from the main
    // component's nearest road, as when the mission was planned, rather than ending the mission.
    if (const auto main = planner::main_component_snap(snapper_, graph_, p.position, snap, {config_.snap_max_distance_m})) {
      auto from_main = endpoints(*main, Role::start, p.heading_deg);
      repair(m, &from_main);
    }
  }
  result.eta_s = m.route.travel_time_s;
  m.route_time_s = now_s;
  emit(position_event(p, now_s, m.row.id, m.route.found ? std::optional<double>(m.route.travel_time_s) : std::nullopt));
  if (!m.route.found || m.route.length_m <= config_.arrival_radius_m ||
      maps::distance_m(snap.point, m.destination_local) <= config_.arrival_radius_m) {
    result.completed = true;
    stage_state(m, MissionState::completed, now_s, staged);
    finish(m, MissionState::completed, now_s, staged);
  } else {
    // The route changed if it is not the rest of the old one from the vehicle's edge on.
    const auto from = std::find(old_edges.begin(), old_edges.end(), m.route.edges.front());
    result.route_changed = !std::equal(from, old_edges.end(), m.route.edges.begin(), m.route.edges.end());
    if (result.route_changed) {
      publish_route(m, reason, now_s, staged);
    } else {
      retime_signals(m, now_s, staged);
    }
  }
  result.durable = submit(staged);
  return result;
}

}  // namespace corridor::server
