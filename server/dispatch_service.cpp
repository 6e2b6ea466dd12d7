#include "server/dispatch_service.hpp"

#include "localizer/match/bearing.hpp"

#include <boost/asio/thread_pool.hpp>
#include <spdlog/spdlog.h>

#include <cmath>

#include "maps/errors.hpp"
#include "maps/intersection_geometry.hpp"
#include "maps/text_id.hpp"
#include "planner/route_geojson.hpp"
#include "planner/snap_points.hpp"
#include "preemption/signal_costs.hpp"
#include "server/dispatch_mission.hpp"
#include "server/realtime_scope.hpp"

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

namespace {

using localizer::angle_between_deg;
// Compass bearing of edge e around offset, degrees clockwise from north.
double bearing_deg(const maps::RoadGraph& g, EdgeId e, double offset_m) { return localizer::road_bearing_deg(g, e, offset_m, 1.0); }

}  // namespace

DispatchService::DispatchService(const maps::RoadGraph& graph, DispatchConfig config, Store* store, double now_s)
    : DispatchService(graph, maps::default_signal_plans(graph), config, store, now_s) {}

DispatchService::DispatchService(const maps::RoadGraph& graph, std::unordered_map<NodeId, maps::SignalPlan> plans,
                                 DispatchConfig config, Store* store, double now_s)
    : DispatchService(graph, maps::signal_map_of(std::move(plans)), config, store, now_s) {}

DispatchService::DispatchService(const maps::RoadGraph& graph, maps::SignalMap signals, DispatchConfig config, Store* store,
                                 double now_s)
    : graph_(graph),
      config_(config),
      store_(store),
      snapper_(graph),
      tracker_(graph, snapper_),
      signals_map_(std::move(signals)),
      overlay_(graph),
      signals_(signals_map_.signals, now_s),
      field_(config.field_controllers.empty()
                 ? nullptr
                 : std::make_unique<ntcip::FieldSignalController>(graph, signals_map_, config.field_controllers, [] {
                     return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
                   })),
      routed_(signals_, field_.get()),
      preemption_(graph, signals_map_.signals, routed_, config.preemption) {
  preemption_.set_signal_nodes(signals_map_.signal_of);
  if (config_.repair_threads < 1 || config_.repair_threads > 64) {
    throw std::invalid_argument("repair_threads must be 1 to 64, not " + std::to_string(config_.repair_threads));
  }
  if (config_.repair_realtime_priority < 0 || config_.repair_realtime_priority > max_realtime_priority()) {
    throw std::invalid_argument("repair_realtime_priority must be 0 (off) to " + std::to_string(max_realtime_priority()) +
                                ", not " + std::to_string(config_.repair_realtime_priority));
  }
  // Every mission's lights are preempted, so each movement through a light with a plan costs its
  // expected transition (the rule the SUMO loop uses too); a signal without a plan keeps the flat
  // expected delay.
  overlay_.set_signal_delay(graph, config_.signal_delay_s);
  preemption::set_signal_costs(overlay_, graph, plans_, preemption::SignalCostRule::preempted);
  if (config_.background_nice < 0 || config_.background_nice > 19) {
    throw std::invalid_argument("background_nice must be 0..19, not " + std::to_string(config_.background_nice));
  }
  if (!(config_.max_hierarchy_density > 0.0)) {
    throw std::invalid_argument("max_hierarchy_density must be positive, not " + std::to_string(config_.max_hierarchy_density));
  }
  if (config_.max_hierarchy_models < 1) {
    throw std::invalid_argument("max_hierarchy_models must be at least 1, not " + std::to_string(config_.max_hierarchy_models));
  }
  if (!(std::isfinite(config_.max_clock_ahead_s) && config_.max_clock_ahead_s >= 0.0)) {
    throw std::invalid_argument("max_clock_ahead_s must be a finite number of seconds >= 0");
  }
  if (config_.planner_graph != PlannerGraph::turn_graph) {
    // `automatic` must build the topology to know its density, and drops it where it is dense.
    const auto started = std::chrono::steady_clock::now();
    hierarchy_ = std::make_unique<SharedHierarchy>(graph, overlay_, config_.max_hierarchy_models);
    const bool keep = config_.planner_graph == PlannerGraph::hierarchy || hierarchy_->density() <= config_.max_hierarchy_density;
    spdlog::info("event=planner_graph choice={} arcs={} arcs_per_vertex={:.1f} built_s={:.2f}", keep ? "hierarchy" : "turn_graph",
                 hierarchy_->topology().arc_count(), hierarchy_->density(),
                 std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count());
    if (!keep) hierarchy_.reset();
  }
  for (EdgeId e : graph.edges()) edges_by_way_.emplace(graph.osm_way(e).v, e);
  if (config_.repair_threads > 1) {
    repair_pool_ = std::make_unique<boost::asio::thread_pool>(static_cast<std::size_t>(config_.repair_threads - 1));
  }
  if (store_ != nullptr) {
    commits_ = std::make_unique<CommitQueue>(*store_, 2048, config_.background_nice);
    restore(now_s);
  }
}

// Queued writes hold copies of what they store, so the queue may drain after the rest is gone.
DispatchService::~DispatchService() {
  if (repair_pool_) repair_pool_->join();
}

void DispatchService::stage(Staged& staged, CommitQueue::Write write) const {
  if (commits_) staged.push_back(std::move(write));
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

void DispatchService::emit(DispatchEvent event) {
  std::lock_guard lock(listeners_mutex_);
  // Numbered under the lock that orders delivery, so every listener sees seq increasing.
  event.seq = next_event_seq_++;
  for (const auto& [id, l] : listeners_) l(event);
}

std::vector<planner::EdgePoint> DispatchService::endpoints(const maps::SnapResult& s, Role role,
                                                           std::optional<double> heading) const {
  auto points = planner::points_from_snap(graph_, s, role == Role::goal ? planner::PointRole::goal : planner::PointRole::start);
  if (!heading || points.size() == 1) return points;
  // A heading picks the direction of travel on a two-way street, or the exit at a junction.
  std::size_t best = 0;
  double best_deg = 360.0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const double d = angle_between_deg(bearing_deg(graph_, points[i].edge, points[i].offset_m), *heading);
    if (d < best_deg) best = i, best_deg = d;
  }
  return {points[best]};
}

// The mission's built-in profile, at its own top speed. A row stored with an unknown profile name
// (by a later version) is resumed as an ambulance (see the resume).
planner::VehicleProfile DispatchService::vehicle_profile(const MissionRow& row) {
  planner::VehicleProfile p = row.profile == "fire_engine" ? planner::fire_engine_profile() : planner::ambulance_profile();
  p.vmax_mps = row.vmax_kmh / 3.6;
  return p;
}

MissionPlanner DispatchService::make_planner(const MissionRow& row, std::vector<planner::EdgePoint> starts,
                                            std::vector<planner::EdgePoint> goals) {
  planner::VehicleProfile profile = vehicle_profile(row);
  if (hierarchy_) {
    if (auto model = hierarchy_->acquire(profile)) return {std::move(model), std::move(starts), std::move(goals)};
    // Every model the hierarchy may hold is in use by other cost models (each is one more
    // customization per congestion batch, and 46 bytes per arc): this one plans on the turn graph.
    spdlog::info("event=mission_on_turn_graph mission={} reason=hierarchy_models_in_use models={}", row.id,
                 hierarchy_->models_in_use());
  }
  return {std::make_unique<planner::TravelCost>(graph_, overlay_, std::move(profile)), std::move(starts), std::move(goals)};
}

std::optional<std::string> DispatchService::repair(Mission& m, const std::vector<planner::EdgePoint>* new_start) {
  std::shared_lock costs(overlay_mutex_);
  std::vector<EdgeId> changed;
  std::vector<ArcBatch> arcs;
  std::optional<std::string> reason;
  {
    std::lock_guard lock(m.pending_mutex);
    changed = std::exchange(m.pending_edges, {});
    arcs = std::exchange(m.pending_arcs, {});
    reason = std::exchange(m.pending_reason, std::nullopt);
  }
  // D* Lite must hear of each change exactly once, before its next repair.
  m.planner.changed(changed, arcs);
  if (new_start != nullptr) m.planner.move_start(*new_start);
  m.planner.replan();
  m.route = m.planner.route();
  return reason;
}

void DispatchService::persist_route(Mission& m, const std::string& reason, double now_s, Staged& staged) {
  // The geometry is rendered by the writer thread, off the request's path; the graph outlives the queue.
  stage(staged, [&graph = graph_, id = m.row.id, revision = m.revision + 1, reason, route = m.route, now_s](Store& store) {
    store.insert_route_revision(id, revision, reason, route.travel_time_s, route.length_m,
                                planner::route_to_geojson(graph, route, "dstar")["geometry"].dump(), now_s);
  });
  ++m.revision;
  m.row.updated_s = now_s;
  m.history.push_back({{m.revision, reason, now_s, m.route.travel_time_s, m.route.length_m, {}}, m.route});
  // A mission that keeps changing its route keeps its latest revisions; the store keeps all.
  constexpr std::size_t kHistoryKept = 200;
  if (m.history.size() > kHistoryKept) m.history.erase(m.history.begin());
}

void DispatchService::retime_signals(Mission& m, double now_s, Staged& staged) {
  auto crossings = preemption::signalized_crossings(graph_, m.route, plans_, now_s);
  for (auto& c : crossings) c.node = signals_map_.key(c.node);
  std::lock_guard lock(preemption_mutex_);
  preemption_.update_route(m.row.id, m.row.priority, crossings, now_s);
  drain_preemption_events(staged);
}

void DispatchService::announce_route(Mission& m, const std::string& reason, double now_s, Staged& staged) {
  DispatchEvent e;
  e.kind = m.revision == 1 ? "mission_created" : "route_changed";
  e.mission = m.row.id;
  e.reason = reason;
  e.time_s = now_s;
  e.vehicle_id = m.row.vehicle_id;
  e.revision = m.revision;
  if (m.route.found) e.eta_s = m.route.travel_time_s;
  emit(std::move(e));
  retime_signals(m, now_s, staged);
}

void DispatchService::publish_route(Mission& m, const std::string& reason, double now_s, Staged& staged) {
  persist_route(m, reason, now_s, staged);
  announce_route(m, reason, now_s, staged);
}

maps::SnapOptions DispatchService::trip_end_snap(bool vehicle_fix) const {
  maps::SnapOptions o{config_.snap_max_distance_m};
  o.skip_ferries = !vehicle_fix;
  return o;
}

bool DispatchService::plan_mission(Mission& m, maps::LatLon start, maps::SnapResult& from, maps::SnapResult& to,
                                   std::optional<double> heading) {
  // The fallback snaps to the main component keep off ferries, as a click does.
  return planner::plan_nearest_or_main(snapper_, graph_, start, from, m.row.destination, to, trip_end_snap(false),
                                       [&](const maps::SnapResult& a, const maps::SnapResult& b) {
                                         m.destination_local = b.point;
                                         auto starts = endpoints(a, Role::start, heading);
                                         auto goals = planner::at_same_node(graph_, a, b) ? starts : endpoints(b, Role::goal, std::nullopt);
                                         m.planner = make_planner(m.row, std::move(starts), std::move(goals));
                                         m.model = m.planner.model();
                                         m.planner.replan();
                                         m.route = m.planner.route();
                                         return m.route.found;
                                       });
}

MissionView DispatchService::create_mission(const MissionRequest& req, double now_s) {
  if (const auto problem = maps::id_problem(req.vehicle_id)) throw bad_request("vehicle_id: the id " + *problem);
  if (!(req.vmax_kmh >= 5.0 && req.vmax_kmh <= 250.0)) throw bad_request("vmax_kmh must be between 5 and 250");
  if (req.priority < 0 || req.priority > 10) throw bad_request("priority must be between 0 and 10");
  std::lock_guard creating(create_mutex_);
  std::optional<maps::LatLon> origin = req.origin;
  std::optional<double> origin_heading;  // a vehicle's own position says which way it faces
  {
    std::shared_lock lock(registry_mutex_);
    if (active_by_vehicle_.count(req.vehicle_id) != 0) {
      throw conflict("vehicle '" + req.vehicle_id + "' already has active mission " +
                     std::to_string(active_by_vehicle_.at(req.vehicle_id)) + "; cancel it first");
    }
    if (!origin) {
      if (auto it = vehicles_.find(req.vehicle_id); it != vehicles_.end()) {
        origin = it->second.position;
        origin_heading = it->second.heading_deg;
      }
    }
  }
  if (!origin) {
    throw unprocessable("no_origin", "vehicle '" + req.vehicle_id +
                                         "' has no known position: post one to /v1/vehicles/{id}/position or give origin");
  }
  maps::SnapResult from, to;
  try {
    from = snapper_.snap(*origin, trip_end_snap(!req.origin));
  } catch (const maps::SnapError& e) {
    throw snap_error(e, "origin");
  }
  try {
    to = snapper_.snap(req.destination, trip_end_snap(false));
  } catch (const maps::SnapError& e) {
    throw snap_error(e, "destination");
  }

  auto m = std::make_shared<Mission>();
  std::unique_lock mission_lock(m->mutex);
  m->row = {next_mission_id_, req.vehicle_id, req.priority, req.vmax_kmh, req.destination, origin, MissionState::active, now_s, now_s,
            req.profile};
  m->last_position = origin;
  Staged staged;
  {
    // Planned and registered under one view of the costs, so no congestion change falls between.
    std::shared_lock costs(overlay_mutex_);
    plan_mission(*m, *origin, from, to, origin_heading);
    m->route_time_s = now_s;
    if (!m->route.found) throw unprocessable("unreachable", "the destination cannot be reached from the origin");
    stage(staged, [row = m->row](Store& store) { store.insert_mission(row); });
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

void DispatchService::stage_state(const Mission& m, MissionState state, double now_s, Staged& staged) const {
  stage(staged, [id = m.row.id, state, now_s](Store& store) { store.update_mission_state(id, state, now_s); });
}

void DispatchService::finish(Mission& m, MissionState state, double now_s, Staged& staged) {
  m.row.state = state;
  m.row.updated_s = now_s;
  {
    // Out of the active list first: no congestion change queues anything for it after this.
    std::lock_guard lock(registry_mutex_);
    active_by_vehicle_.erase(m.row.vehicle_id);
  }
  // A finished mission keeps its last route, not its search state nor its hold on a shared model.
  m.planner.reset();
  {
    std::lock_guard lock(m.pending_mutex);
    m.pending_edges = {};
    m.pending_arcs = {};
  }
  {
    std::lock_guard lock(preemption_mutex_);
    preemption_.cancel(m.row.id, now_s);
    m.final_schedule = preemption_.schedule(m.row.id);
    preemption_.forget(m.row.id, now_s);
    drain_preemption_events(staged);
  }
  DispatchEvent e;
  e.kind = state == MissionState::completed ? "mission_completed" : "mission_cancelled";
  e.mission = m.row.id;
  e.time_s = now_s;
  e.vehicle_id = m.row.vehicle_id;
  emit(std::move(e));
}

MissionView DispatchService::cancel_mission(MissionId id, double now_s) {
  const MissionPtr m = find(id);
  std::unique_lock lock(m->mutex);
  require_active(*m);
  Staged staged;
  // Stored first: if that fails, the mission is still active everywhere.
  stage_state(*m, MissionState::cancelled, now_s, staged);
  submit(staged)->wait();
  finish(*m, MissionState::cancelled, now_s, staged);
  auto durable = submit(staged);
  MissionView cancelled = view(*m);
  lock.unlock();
  durable->wait();
  return cancelled;
}

std::size_t DispatchService::active_mission_count() const {
  std::shared_lock lock(registry_mutex_);
  return active_by_vehicle_.size();
}

std::optional<bool> DispatchService::repair_realtime_granted() const {
  switch (repair_realtime_.load()) {
    case Realtime::granted: return true;
    case Realtime::denied: return false;
    case Realtime::not_asked: break;
  }
  return std::nullopt;
}

}  // namespace corridor::server
