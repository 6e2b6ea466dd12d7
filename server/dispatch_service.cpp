#include "server/dispatch_service.hpp"

#include <boost/asio/post.hpp>
#include <boost/asio/thread_pool.hpp>
#include <spdlog/spdlog.h>

#include <atomic>
#include <cmath>
#include <exception>
#include <latch>

#include "maps/errors.hpp"
#include "maps/intersection_geometry.hpp"
#include "planner/route_geojson.hpp"
#include "planner/snap_points.hpp"

namespace corridor::server {

const char* to_string(MissionState s) {
  switch (s) {
    case MissionState::active: return "active";
    case MissionState::completed: return "completed";
    case MissionState::cancelled: return "cancelled";
  }
  return "?";
}

std::optional<MissionState> mission_state_from(const std::string& s) {
  for (MissionState m : {MissionState::active, MissionState::completed, MissionState::cancelled}) {
    if (s == to_string(m)) return m;
  }
  return std::nullopt;
}

struct DispatchService::Mission {
  // Confines everything below but the pending changes: one request works on a mission at a time.
  mutable std::mutex mutex;
  MissionRow row;
  std::optional<maps::LatLon> last_position;
  maps::Point2 destination_local;
  std::unique_ptr<planner::TravelCost> cost;
  std::unique_ptr<planner::DStarLite> planner;
  planner::Route route;
  std::uint32_t revision = 0;
  std::vector<preemption::ScheduleEntry> final_schedule;  // kept when the engine forgets the mission

  // Edges whose cost changed since the planner last heard, and the reason to give if the repaired
  // route differs. Appended under the overlay's exclusive lock, taken under its shared lock, so a
  // repair sees exactly the costs it was told of.
  std::mutex pending_mutex;
  std::vector<EdgeId> pending_edges;
  std::optional<std::string> pending_reason;
};

namespace {

ApiError snap_error(const maps::SnapError& e, const char* what) {
  const char* code = e.reason() == maps::SnapError::Reason::invalid_coordinate ? "invalid_coordinate"
                     : e.reason() == maps::SnapError::Reason::outside_map  ? "outside_map"
                                                                            : "off_road";
  return unprocessable(code, std::string(what) + ": " + e.what());
}

// Compass bearing of edge e around offset, degrees clockwise from north.
double bearing_deg(const maps::RoadGraph& g, EdgeId e, double offset_m) {
  const double len = g.length_m(e);
  const maps::Point2 a = g.point_along(e, std::max(0.0, offset_m - 1.0));
  const maps::Point2 b = g.point_along(e, std::min(len, offset_m + 1.0));
  return std::fmod(std::atan2(b.x_m - a.x_m, b.y_m - a.y_m) * 180.0 / M_PI + 360.0, 360.0);
}

double angle_between_deg(double a, double b) {
  const double d = std::fmod(std::abs(a - b), 360.0);
  return d > 180.0 ? 360.0 - d : d;
}

}  // namespace


DispatchService::DispatchService(const maps::RoadGraph& graph, DispatchConfig config, Store* store, double now_s)
    : DispatchService(graph, maps::default_signal_plans(graph), config, store, now_s) {}

DispatchService::DispatchService(const maps::RoadGraph& graph, std::unordered_map<NodeId, maps::SignalPlan> plans,
                                 DispatchConfig config, Store* store, double now_s)
    : graph_(graph),
      config_(config),
      store_(store),
      snapper_(graph),
      plans_(std::move(plans)),
      overlay_(graph),
      signals_(plans_, now_s),
      preemption_(graph, plans_, signals_, config.preemption) {
  if (config_.repair_threads < 1 || config_.repair_threads > 64) {
    throw std::invalid_argument("repair_threads must be 1 to 64, not " + std::to_string(config_.repair_threads));
  }
  overlay_.set_signal_delay(graph, config_.signal_delay_s);
  for (EdgeId e : graph.edges()) edges_by_way_.emplace(graph.osm_way(e).v, e);
  if (config_.repair_threads > 1) {
    repair_pool_ = std::make_unique<boost::asio::thread_pool>(static_cast<std::size_t>(config_.repair_threads - 1));
  }
  if (store_ != nullptr) {
    commits_ = std::make_unique<CommitQueue>(*store_);
    restore(now_s);
  }
}

// Queued writes hold copies of what they store, so the queue may drain after the rest is gone.
DispatchService::~DispatchService() {
  if (repair_pool_) repair_pool_->join();
}

std::shared_ptr<CommitTicket> DispatchService::submit(Staged& staged) {
  if (!commits_ || staged.empty()) return CommitTicket::done();
  return commits_->submit([writes = std::exchange(staged, {})](Store& store) {
    for (const auto& w : writes) w(store);
  });
}

void DispatchService::flush() {
  if (commits_) commits_->flush();
}

std::optional<CommitQueue::Stats> DispatchService::commit_stats() const {
  if (!commits_) return std::nullopt;
  return commits_->stats();
}

std::size_t DispatchService::subscribe(Listener listener) {
  std::lock_guard lock(listeners_mutex_);
  listeners_[next_listener_] = std::move(listener);
  return next_listener_++;
}

void DispatchService::unsubscribe(std::size_t id) {
  std::lock_guard lock(listeners_mutex_);
  listeners_.erase(id);
}

void DispatchService::emit(const std::string& kind, MissionId mission, const std::string& reason, double now_s) {
  const DispatchEvent event{kind, mission, reason, now_s};
  std::lock_guard lock(listeners_mutex_);
  for (const auto& [id, l] : listeners_) l(event);
}

std::vector<planner::EdgePoint> DispatchService::endpoints(const maps::SnapResult& s, Role role,
                                                           std::optional<double> heading) const {
  auto points = planner::points_from_snap(graph_, s, role == Role::goal ? planner::PointRole::goal : planner::PointRole::start);
  if (!heading || points.size() == 1) return points;
  // A heading picks the direction of travel on a two-way street.
  const double a = angle_between_deg(bearing_deg(graph_, points[0].edge, points[0].offset_m), *heading);
  const double b = angle_between_deg(bearing_deg(graph_, points[1].edge, points[1].offset_m), *heading);
  return {a <= b ? points[0] : points[1]};
}

MissionView DispatchService::view(const Mission& m) const {
  MissionView v;
  v.id = m.row.id;
  v.vehicle_id = m.row.vehicle_id;
  v.state = m.row.state;
  v.priority = m.row.priority;
  v.vmax_kmh = m.row.vmax_kmh;
  v.destination = m.row.destination;
  v.last_position = m.last_position;
  v.route = m.route;
  v.route_revision = m.revision;
  if (m.row.state == MissionState::active) {
    std::lock_guard lock(preemption_mutex_);
    v.schedule = preemption_.schedule(m.row.id);
  } else {
    v.schedule = m.final_schedule;
  }
  v.created_s = m.row.created_s;
  v.updated_s = m.row.updated_s;
  return v;
}

void DispatchService::drain_preemption_events(Staged& staged) {
  for (const auto& e : preemption_.take_events()) {
    if (commits_) staged.push_back([e](Store& store) { store.insert_preemption_event(e); });
    emit("preemption_" + e.kind, e.mission, e.detail, e.time_s);
  }
}

std::optional<std::string> DispatchService::repair(Mission& m, const std::vector<planner::EdgePoint>* new_start) {
  std::shared_lock costs(overlay_mutex_);
  std::vector<EdgeId> changed;
  std::optional<std::string> reason;
  {
    std::lock_guard lock(m.pending_mutex);
    changed = std::exchange(m.pending_edges, {});
    reason = std::exchange(m.pending_reason, std::nullopt);
  }
  // D* Lite must hear of each change exactly once, before its next repair.
  if (!changed.empty()) m.planner->edges_changed(changed);
  if (new_start != nullptr) m.planner->move_start(*new_start);
  m.planner->replan();
  m.route = m.planner->route();
  return reason;
}

void DispatchService::persist_route(Mission& m, const std::string& reason, double now_s, Staged& staged) {
  if (commits_) {
    // The geometry is rendered by the writer thread, off the request's path; the graph outlives the queue.
    staged.push_back([&graph = graph_, id = m.row.id, revision = m.revision + 1, reason, route = m.route, now_s](Store& store) {
      store.insert_route_revision(id, revision, reason, route.travel_time_s, route.length_m,
                                  planner::route_to_geojson(graph, route, "dstar")["geometry"].dump(), now_s);
    });
  }
  ++m.revision;
  m.row.updated_s = now_s;
}

void DispatchService::retime_signals(Mission& m, double now_s, Staged& staged) {
  const auto crossings = preemption::signalized_crossings(m.route, plans_, now_s);
  std::lock_guard lock(preemption_mutex_);
  preemption_.update_route(m.row.id, m.row.priority, crossings, now_s);
  drain_preemption_events(staged);
}

void DispatchService::announce_route(Mission& m, const std::string& reason, double now_s, Staged& staged) {
  emit(m.revision == 1 ? "mission_created" : "route_changed", m.row.id, reason, now_s);
  retime_signals(m, now_s, staged);
}

MissionView DispatchService::create_mission(const MissionRequest& req, double now_s) {
  if (req.vehicle_id.empty() || req.vehicle_id.size() > 64) throw bad_request("vehicle_id must be 1 to 64 characters");
  if (!(req.vmax_kmh >= 5.0 && req.vmax_kmh <= 250.0)) throw bad_request("vmax_kmh must be between 5 and 250");
  if (req.priority < 0 || req.priority > 10) throw bad_request("priority must be between 0 and 10");
  std::lock_guard creating(create_mutex_);
  std::optional<maps::LatLon> origin = req.origin;
  {
    std::shared_lock lock(registry_mutex_);
    if (active_by_vehicle_.count(req.vehicle_id) != 0) {
      throw conflict("vehicle '" + req.vehicle_id + "' already has active mission " +
                     std::to_string(active_by_vehicle_.at(req.vehicle_id)) + "; cancel it first");
    }
    if (!origin) {
      if (auto it = last_position_.find(req.vehicle_id); it != last_position_.end()) origin = it->second;
    }
  }
  if (!origin) {
    throw unprocessable("no_origin", "vehicle '" + req.vehicle_id +
                                         "' has no known position: post one to /v1/vehicles/{id}/position or give origin");
  }
  maps::SnapResult from, to;
  try {
    from = snapper_.snap(*origin, {config_.snap_max_distance_m});
  } catch (const maps::SnapError& e) {
    throw snap_error(e, "origin");
  }
  try {
    to = snapper_.snap(req.destination, {config_.snap_max_distance_m});
  } catch (const maps::SnapError& e) {
    throw snap_error(e, "destination");
  }

  auto m = std::make_shared<Mission>();
  std::unique_lock mission_lock(m->mutex);
  m->row = {next_mission_id_, req.vehicle_id, req.priority, req.vmax_kmh, req.destination, origin, MissionState::active, now_s, now_s};
  m->last_position = origin;
  m->destination_local = to.point;
  m->cost = std::make_unique<planner::TravelCost>(graph_, overlay_, planner::VehicleProfile{req.vmax_kmh / 3.6});
  Staged staged;
  {
    // Planned and registered under one view of the costs, so no congestion change falls between.
    std::shared_lock costs(overlay_mutex_);
    m->planner = std::make_unique<planner::DStarLite>(*m->cost, endpoints(from, Role::start, std::nullopt),
                                                      endpoints(to, Role::goal, std::nullopt));
    m->planner->replan();
    m->route = m->planner->route();
    if (!m->route.found) throw unprocessable("unreachable", "the destination cannot be reached from the origin");
    if (commits_) staged.push_back([row = m->row](Store& store) { store.insert_mission(row); });
    persist_route(*m, "dispatch", now_s, staged);
    // The database first: if it fails, nothing was shared and the request fails whole.
    submit(staged)->wait();
    ++next_mission_id_;
    std::lock_guard lock(registry_mutex_);
    missions_[m->row.id] = m;
    active_by_vehicle_[m->row.vehicle_id] = m->row.id;
  }
  announce_route(*m, "dispatch", now_s, staged);
  auto durable = submit(staged);
  MissionView created = view(*m);
  mission_lock.unlock();
  durable->wait();
  return created;
}

MissionView DispatchService::mission(MissionId id) const {
  MissionPtr m;
  {
    std::shared_lock lock(registry_mutex_);
    auto it = missions_.find(id);
    if (it == missions_.end()) throw not_found("no mission " + std::to_string(id));
    m = it->second;
  }
  std::lock_guard lock(m->mutex);
  return view(*m);
}

std::vector<MissionView> DispatchService::missions(std::optional<MissionState> state) const {
  std::vector<MissionPtr> all;
  {
    std::shared_lock lock(registry_mutex_);
    for (const auto& [id, m] : missions_) all.push_back(m);
  }
  std::vector<MissionView> out;
  for (const auto& m : all) {
    std::lock_guard lock(m->mutex);
    if (!state || m->row.state == *state) out.push_back(view(*m));
  }
  return out;
}

DispatchService::MissionPtr DispatchService::find(MissionId id) const {
  std::shared_lock lock(registry_mutex_);
  auto it = missions_.find(id);
  if (it == missions_.end()) throw not_found("no mission " + std::to_string(id));
  return it->second;
}

void DispatchService::require_active(const Mission& m) {
  if (m.row.state != MissionState::active) {
    throw conflict("mission " + std::to_string(m.row.id) + " is already " + to_string(m.row.state));
  }
}

void DispatchService::stage_state(const Mission& m, MissionState state, double now_s, Staged& staged) {
  staged.push_back([id = m.row.id, state, now_s](Store& store) { store.update_mission_state(id, state, now_s); });
}

void DispatchService::finish(Mission& m, MissionState state, double now_s, Staged& staged) {
  m.row.state = state;
  m.row.updated_s = now_s;
  m.planner.reset();  // a finished mission keeps its last route, not its search state
  {
    std::lock_guard lock(preemption_mutex_);
    preemption_.cancel(m.row.id, now_s);
    m.final_schedule = preemption_.schedule(m.row.id);
    preemption_.forget(m.row.id, now_s);
    drain_preemption_events(staged);
  }
  {
    std::lock_guard lock(registry_mutex_);
    active_by_vehicle_.erase(m.row.vehicle_id);
  }
  emit(state == MissionState::completed ? "mission_completed" : "mission_cancelled", m.row.id, "", now_s);
}

MissionView DispatchService::cancel_mission(MissionId id, double now_s) {
  const MissionPtr m = find(id);
  std::unique_lock lock(m->mutex);
  require_active(*m);
  Staged staged;
  // Stored first: if that fails, the mission is still active everywhere.
  if (commits_) stage_state(*m, MissionState::cancelled, now_s, staged);
  submit(staged)->wait();
  finish(*m, MissionState::cancelled, now_s, staged);
  auto durable = submit(staged);
  MissionView cancelled = view(*m);
  lock.unlock();
  durable->wait();
  return cancelled;
}

PositionResult DispatchService::report_position(const PositionReport& p, double now_s) {
  if (p.vehicle_id.empty() || p.vehicle_id.size() > 64) throw bad_request("vehicle id must be 1 to 64 characters");
  if (p.source != "gps" && p.source != "vo") throw bad_request("source must be \"gps\" or \"vo\"");
  if (p.heading_deg && !(std::isfinite(*p.heading_deg) && *p.heading_deg >= 0.0 && *p.heading_deg <= 360.0)) {
    throw bad_request("heading_deg must be within [0, 360]");
  }
  if (p.speed_mps && !(std::isfinite(*p.speed_mps) && *p.speed_mps >= 0.0 && *p.speed_mps < 150.0)) {
    throw bad_request("speed_mps must be within [0, 150)");
  }
  if (p.hdop && !(std::isfinite(*p.hdop) && *p.hdop >= 0.0)) throw bad_request("hdop must be a number >= 0");
  if (!std::isfinite(p.timestamp_s)) throw bad_request("timestamp must be a finite number of seconds");
  maps::SnapResult snap;
  try {
    snap = snapper_.snap(p.position, {config_.snap_max_distance_m});
  } catch (const maps::SnapError& e) {
    throw snap_error(e, "position");
  }

  PositionResult result;
  result.snap_distance_m = snap.distance_m;
  MissionPtr mp;
  {
    std::lock_guard lock(registry_mutex_);
    last_position_[p.vehicle_id] = p.position;
    if (auto it = active_by_vehicle_.find(p.vehicle_id); it != active_by_vehicle_.end()) mp = missions_.at(it->second);
  }
  Staged staged;
  std::unique_lock<std::mutex> lock;
  if (mp) {
    lock = std::unique_lock(mp->mutex);
    if (mp->row.state != MissionState::active) mp.reset();  // it ended in between
  }
  if (!mp) {
    if (commits_) staged.push_back([p, now_s](Store& store) { store.insert_position(p, std::nullopt, now_s); });
    result.durable = submit(staged);
    return result;
  }
  Mission& m = *mp;
  result.mission = m.row.id;
  if (commits_) staged.push_back([p, id = m.row.id, now_s](Store& store) { store.insert_position(p, id, now_s); });
  m.last_position = p.position;

  // Signals behind the vehicle: every intersection of the old route before its current edge.
  const auto points = endpoints(snap, Role::start, p.heading_deg);
  const auto pos_in_route = std::find_if(m.route.edges.begin(), m.route.edges.end(), [&](EdgeId e) {
    return std::any_of(points.begin(), points.end(), [&](const planner::EdgePoint& q) { return q.edge == e; });
  });
  if (pos_in_route != m.route.edges.end()) {
    const auto passed = static_cast<std::size_t>(pos_in_route - m.route.edges.begin());
    std::lock_guard signals(preemption_mutex_);
    for (std::size_t i = 0; i < passed && i < m.route.nodes.size(); ++i) preemption_.vehicle_passed(m.row.id, m.route.nodes[i], now_s);
  }

  const std::vector<EdgeId> old_edges = m.route.edges;
  // This repair also covers any cost change the planner heard of since its last one.
  const std::string reason = repair(m, &points).value_or("off_route");
  result.eta_s = m.route.travel_time_s;
  emit("position", m.row.id, p.source, now_s);
  if (!m.route.found || m.route.length_m <= config_.arrival_radius_m ||
      maps::distance_m(snap.point, m.destination_local) <= config_.arrival_radius_m) {
    result.completed = true;
    if (commits_) stage_state(m, MissionState::completed, now_s, staged);
    finish(m, MissionState::completed, now_s, staged);
  } else {
    // The route changed if it is not the rest of the old one from the vehicle's edge on.
    const auto from = std::find(old_edges.begin(), old_edges.end(), m.route.edges.front());
    result.route_changed = !std::equal(from, old_edges.end(), m.route.edges.begin(), m.route.edges.end());
    if (result.route_changed) {
      persist_route(m, reason, now_s, staged);
      announce_route(m, reason, now_s, staged);
    } else {
      retime_signals(m, now_s, staged);
    }
  }
  result.durable = submit(staged);
  return result;
}

std::vector<EdgeId> DispatchService::resolve_edges(const CongestionUpdate& u) const {
  if (u.edge.has_value() == u.osm_way_id.has_value()) throw bad_request("each update needs exactly one of edge, osm_way_id");
  if (u.edge) {
    if (!u.edge->valid() || u.edge->index() >= graph_.edge_count()) {
      throw unprocessable("unknown_edge", "edge " + std::to_string(u.edge->v) + " is not in the map (it has " +
                                              std::to_string(graph_.edge_count()) + " edges)");
    }
    return {*u.edge};
  }
  std::vector<EdgeId> out;
  auto [lo, hi] = edges_by_way_.equal_range(*u.osm_way_id);
  for (auto it = lo; it != hi; ++it) out.push_back(it->second);
  if (out.empty()) throw unprocessable("unknown_way", "OSM way " + std::to_string(*u.osm_way_id) + " is not in the map");
  return out;
}

CongestionResult DispatchService::report_congestion(const std::vector<CongestionUpdate>& updates, double now_s) {
  const auto started = std::chrono::steady_clock::now();
  if (updates.empty()) throw bad_request("updates must hold at least one update");
  if (updates.size() > 10000) throw bad_request("at most 10000 updates per request");
  // Validate everything before changing anything: a request applies whole or not at all.
  std::vector<std::pair<EdgeId, planner::EdgeCondition>> changes;
  std::vector<std::optional<double>> expiry;
  for (const CongestionUpdate& u : updates) {
    const int given = (u.speed_kmh ? 1 : 0) + (u.travel_time_s ? 1 : 0) + (u.factor ? 1 : 0);
    if (given != 1) throw bad_request("each update needs exactly one of speed_kmh, travel_time_s, factor");
    if (u.expires_in_s && !(std::isfinite(*u.expires_in_s) && *u.expires_in_s > 0.0)) {
      throw bad_request("expires_in_s must be a positive number of seconds");
    }
    if (u.speed_kmh && !(std::isfinite(*u.speed_kmh) && *u.speed_kmh >= 0.0 && *u.speed_kmh < 400.0)) {
      throw bad_request("speed_kmh must be within [0, 400); 0 closes the road");
    }
    if (u.travel_time_s && !(std::isfinite(*u.travel_time_s) && *u.travel_time_s > 0.0)) {
      throw bad_request("travel_time_s must be a positive number of seconds");
    }
    if (u.factor && !(*u.factor > 0.0) ) throw bad_request("factor must be positive (a very large factor closes the road)");
    const std::vector<EdgeId> edges = resolve_edges(u);
    // travel_time_s is the time of the whole edge or way (each road counted once, not per direction).
    double free_flow_s = 0.0;
    for (EdgeId e : edges) {
      if (!graph_.twin(e).valid() || e < graph_.twin(e) || edges.size() == 1) free_flow_s += graph_.length_m(e) / graph_.speed_mps(e);
    }
    for (EdgeId e : edges) {
      double factor = 1.0;
      if (u.factor) factor = *u.factor;
      if (u.speed_kmh) factor = *u.speed_kmh <= 0.0 ? planner::kInfCost : (graph_.speed_mps(e) * 3.6) / *u.speed_kmh;
      if (u.travel_time_s) factor = *u.travel_time_s / free_flow_s;
      changes.push_back({e, {factor, 0.0}});
      expiry.push_back(u.expires_in_s ? std::optional<double>(now_s + *u.expires_in_s) : std::nullopt);
    }
  }

  // One congestion change at a time, end to end; positions do not wait for it.
  std::lock_guard serial(congestion_mutex_);
  {
    // A speed or factor update keeps the edge's queue delay.
    std::shared_lock costs(overlay_mutex_);
    for (auto& [e, condition] : changes) condition.queue_delay_s = overlay_.edge(e).queue_delay_s;
  }
  // Persist the whole batch before applying any of it, so a storage failure changes nothing.
  if (commits_) {
    commits_->run([&](Store& store) {
      for (std::size_t i = 0; i < changes.size(); ++i) store.insert_congestion(changes[i].first, changes[i].second, expiry[i], now_s);
    });
  }
  for (std::size_t i = 0; i < changes.size(); ++i) {
    const std::uint64_t seq = ++update_sequence_;
    latest_update_[changes[i].first] = seq;
    if (expiry[i]) expiries_.emplace(*expiry[i], std::make_pair(changes[i].first, seq));
  }
  const std::vector<MissionPtr> affected = apply_changes(changes, "congestion");
  emit("congestion_applied", 0, std::to_string(changes.size()) + " edges", now_s);
  std::vector<std::shared_ptr<CommitTicket>> durable;
  CongestionResult result = repair_plans(affected, now_s, started, durable);
  result.edges_changed = changes.size();
  for (const auto& t : durable) t->wait();
  return result;
}

std::vector<DispatchService::MissionPtr> DispatchService::apply_changes(
    const std::vector<std::pair<EdgeId, planner::EdgeCondition>>& changes, const std::string& reason) {
  std::vector<EdgeId> edges;
  edges.reserve(changes.size());
  for (const auto& [e, condition] : changes) edges.push_back(e);
  std::vector<MissionPtr> affected;
  std::lock_guard costs(overlay_mutex_);
  for (const auto& [e, condition] : changes) overlay_.set_edge(e, condition);
  std::shared_lock registry(registry_mutex_);
  for (const auto& [vehicle, id] : active_by_vehicle_) {
    const MissionPtr& m = missions_.at(id);
    std::lock_guard lock(m->pending_mutex);
    m->pending_edges.insert(m->pending_edges.end(), edges.begin(), edges.end());
    m->pending_reason = reason;
    affected.push_back(m);
  }
  return affected;
}

void DispatchService::repair_one(Mission& m, double now_s, CongestionResult& result,
                                 std::vector<std::shared_ptr<CommitTicket>>& durable) {
  std::lock_guard lock(m.mutex);
  if (m.row.state != MissionState::active) return;
  ++result.missions_replanned;
  const std::vector<EdgeId> before = m.route.edges;
  const auto started = std::chrono::steady_clock::now();
  const std::optional<std::string> reason = repair(m, nullptr);
  const double took_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  result.slowest_replan_s = std::max(result.slowest_replan_s, took_s);
  result.mission_replan_s.push_back(took_s);
  if (!reason) return;  // a position report repaired it in the meantime
  Staged staged;
  if (m.route.edges != before) {
    ++result.routes_changed;
    persist_route(m, *reason, now_s, staged);
    announce_route(m, *reason, now_s, staged);
  } else {
    // Same route, new costs: the arrival times moved, so the signals are re-timed.
    retime_signals(m, now_s, staged);
  }
  durable.push_back(submit(staged));
}

CongestionResult DispatchService::repair_plans(const std::vector<MissionPtr>& missions, double now_s,
                                               std::chrono::steady_clock::time_point started,
                                               std::vector<std::shared_ptr<CommitTicket>>& durable) {
  CongestionResult result;
  // The calling thread and the pool's take missions off one counter; a mission's own lock keeps
  // position reports out of its plan while it is repaired, and lets other missions' reports through.
  std::atomic<std::size_t> next{0};
  std::mutex merge_mutex;
  std::exception_ptr failure;
  const auto drain = [&] {
    CongestionResult mine;
    std::vector<std::shared_ptr<CommitTicket>> tickets;
    try {
      for (std::size_t i = next++; i < missions.size(); i = next++) repair_one(*missions[i], now_s, mine, tickets);
    } catch (...) {
      std::lock_guard lock(merge_mutex);
      if (!failure) failure = std::current_exception();
    }
    std::lock_guard lock(merge_mutex);
    result.missions_replanned += mine.missions_replanned;
    result.routes_changed += mine.routes_changed;
    result.slowest_replan_s = std::max(result.slowest_replan_s, mine.slowest_replan_s);
    result.mission_replan_s.insert(result.mission_replan_s.end(), mine.mission_replan_s.begin(), mine.mission_replan_s.end());
    durable.insert(durable.end(), tickets.begin(), tickets.end());
  };
  const std::size_t helpers =
      repair_pool_ ? std::min(static_cast<std::size_t>(config_.repair_threads - 1), missions.size() / 2) : 0;
  std::latch helpers_done(static_cast<std::ptrdiff_t>(helpers));
  for (std::size_t h = 0; h < helpers; ++h) {
    boost::asio::post(*repair_pool_, [&] {
      drain();
      helpers_done.count_down();
    });
  }
  drain();
  helpers_done.wait();
  if (failure) std::rethrow_exception(failure);
  result.replan_latency_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  return result;
}

void DispatchService::report_counts(NodeId node, maps::Compass approach, double arrivals, double departures, double now_s) {
  if (plans_.count(node) == 0) throw not_found("no signal at node " + std::to_string(node.v));
  std::lock_guard lock(preemption_mutex_);
  try {
    preemption_.record_counts(node, approach, now_s, arrivals, departures);
  } catch (const preemption::CountError& e) {
    throw bad_request(e.what());
  }
}

void DispatchService::tick(double now_s) {
  {
    std::lock_guard serial(congestion_mutex_);
    std::vector<std::pair<EdgeId, planner::EdgeCondition>> expired;
    while (!expiries_.empty() && expiries_.begin()->first <= now_s) {
      const auto [e, seq] = expiries_.begin()->second;
      expiries_.erase(expiries_.begin());
      // An expiry ends only the update it came with; a later update of the edge stays in force.
      if (latest_update_[e] != seq) continue;
      latest_update_.erase(e);
      expired.push_back({e, planner::EdgeCondition{}});
    }
    if (!expired.empty()) {
      // Nobody waits for the tick's writes; a failure is logged by the queue.
      std::vector<std::shared_ptr<CommitTicket>> durable;
      repair_plans(apply_changes(expired, "congestion_expired"), now_s, std::chrono::steady_clock::now(), durable);
    }
  }
  Staged staged;
  {
    std::lock_guard lock(preemption_mutex_);
    signals_.advance(now_s);
    preemption_.tick(now_s);
    drain_preemption_events(staged);
  }
  submit(staged);
}

std::vector<preemption::Light> DispatchService::signal_lights(NodeId node) const {
  if (plans_.count(node) == 0) throw not_found("no signal at node " + std::to_string(node.v));
  std::lock_guard lock(preemption_mutex_);
  return signals_.lights(node);
}

std::pair<std::string, std::size_t> DispatchService::signal_mode(NodeId node) const {
  if (plans_.count(node) == 0) throw not_found("no signal at node " + std::to_string(node.v));
  std::lock_guard lock(preemption_mutex_);
  const char* mode = signals_.mode(node) == preemption::SignalMode::held ? "held"
                     : signals_.running_program(node)                    ? "program"
                                                                         : "clearing";
  return {mode, signals_.program_step(node)};
}

std::size_t DispatchService::active_mission_count() const {
  std::shared_lock lock(registry_mutex_);
  return active_by_vehicle_.size();
}

// Runs in the constructor, before the service is shared: no locks needed.
void DispatchService::restore(double now_s) {
  for (const CongestionRow& c : store_->congestion_in_force(now_s)) {
    if (c.edge.index() >= graph_.edge_count()) continue;  // recorded against another map
    overlay_.set_edge(c.edge, c.condition);
    const std::uint64_t seq = ++update_sequence_;
    latest_update_[c.edge] = seq;
    if (c.expires_at_s) expiries_.emplace(*c.expires_at_s, std::make_pair(c.edge, seq));
  }
  Staged staged;
  for (const MissionRow& row : store_->missions(std::nullopt)) {
    next_mission_id_ = std::max(next_mission_id_, row.id + 1);
    const auto last = store_->last_position(row.vehicle_id);
    if (row.state != MissionState::active) {
      // Finished missions stay readable; they need no planner.
      auto m = std::make_shared<Mission>();
      m->row = row;
      if (last) m->last_position = last->position;
      missions_[row.id] = std::move(m);
      continue;
    }
    const maps::LatLon start = last ? last->position : row.origin.value_or(row.destination);
    try {
      const auto from = snapper_.snap(start, {config_.snap_max_distance_m});
      const auto to = snapper_.snap(row.destination, {config_.snap_max_distance_m});
      auto m = std::make_shared<Mission>();
      m->row = row;
      m->last_position = start;
      m->destination_local = to.point;
      m->cost = std::make_unique<planner::TravelCost>(graph_, overlay_, planner::VehicleProfile{row.vmax_kmh / 3.6});
      m->planner = std::make_unique<planner::DStarLite>(
          *m->cost, endpoints(from, Role::start, last ? last->heading_deg : std::nullopt),
          endpoints(to, Role::goal, std::nullopt));
      m->planner->replan();
      m->route = m->planner->route();
      missions_[row.id] = m;
      active_by_vehicle_[row.vehicle_id] = row.id;
      last_position_[row.vehicle_id] = start;
      persist_route(*m, "restart", now_s, staged);
      announce_route(*m, "restart", now_s, staged);
      spdlog::info("event=mission_resumed mission={} vehicle={}", row.id, row.vehicle_id);
    } catch (const maps::SnapError& e) {
      spdlog::error("event=mission_not_resumable mission={} reason=\"{}\"", row.id, e.what());
    }
  }
  submit(staged)->wait();
}

}  // namespace corridor::server
