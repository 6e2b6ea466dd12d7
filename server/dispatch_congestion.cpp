// The dispatch service's congestion side: validating and storing congestion reports, applying
// them and their expiries to the shared costs, repairing every affected mission's plan over the
// repair threads, and the periodic tick (expiries, then the signals).
#include "server/dispatch_service.hpp"

#include <boost/asio/post.hpp>
#include <boost/asio/thread_pool.hpp>
#include <spdlog/spdlog.h>

#include <time.h>

#include <atomic>
#include <cmath>
#include <exception>
#include <latch>

#include "server/dispatch_mission.hpp"
#include "server/realtime_scope.hpp"

namespace corridor::server {

namespace {

// The calling thread's CPU time (one system call, about 1 µs here).
double thread_cpu_s() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + static_cast<double>(t.tv_nsec) * 1e-9;
}

}  // namespace

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
    if (u.factor && !(*u.factor > 0.0)) throw bad_request("factor must be positive (a very large factor closes the road)");
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
  double customization_s = 0;
  const std::vector<MissionPtr> affected = apply_changes(changes, "congestion", customization_s);
  DispatchEvent applied;
  applied.kind = "congestion_applied";
  applied.reason = std::to_string(changes.size()) + " edges";
  applied.time_s = now_s;
  applied.edges_changed = changes.size();
  emit(std::move(applied));
  std::vector<std::shared_ptr<CommitTicket>> durable;
  CongestionResult result = repair_plans(affected, now_s, started, durable);
  result.edges_changed = changes.size();
  result.customization_s = customization_s;
  for (const auto& t : durable) t->wait();
  return result;
}

std::vector<DispatchService::MissionPtr> DispatchService::apply_changes(
    const std::vector<std::pair<EdgeId, planner::EdgeCondition>>& changes, const std::string& reason,
    double& customization_s) {
  std::vector<EdgeId> edges;
  edges.reserve(changes.size());
  for (const auto& [e, condition] : changes) edges.push_back(e);
  std::vector<MissionPtr> affected;
  std::lock_guard costs(overlay_mutex_);
  for (const auto& [e, condition] : changes) overlay_.set_edge(e, condition);
  // The metrics follow the overlay before any repair can read them: one customization per model,
  // whatever the number of missions on it.
  std::vector<std::pair<std::shared_ptr<const HierarchyModel>, ArcBatch>> batches;
  if (hierarchy_) {
    const auto started = std::chrono::steady_clock::now();
    batches = hierarchy_->edges_changed(edges);
    customization_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  }
  std::shared_lock registry(registry_mutex_);
  for (const auto& [vehicle, id] : active_by_vehicle_) {
    const MissionPtr& m = missions_.at(id);
    std::lock_guard lock(m->pending_mutex);
    m->pending_edges.insert(m->pending_edges.end(), edges.begin(), edges.end());
    for (const auto& [model, arcs] : batches) {
      if (model.get() == m->model) m->pending_arcs.push_back(arcs);
    }
    m->pending_reason = reason;
    affected.push_back(m);
  }
  return affected;
}

void DispatchService::repair_one(Mission& m, double now_s, CongestionResult& result,
                                 std::vector<std::shared_ptr<CommitTicket>>& durable) {
  // The wall clock starts before the mission's lock: a position report holding it (on an I/O
  // thread, at a lower priority) is part of what the repair waits for.
  const auto started = std::chrono::steady_clock::now();
  std::lock_guard lock(m.mutex);
  if (m.row.state != MissionState::active) return;
  ++result.missions_replanned;
  const std::vector<EdgeId> before = m.route.edges;
  // The CPU clock is read inside the wall clock's window: a system call is where a pending
  // preemption takes effect, and one just before the window would hide the wait from it.
  const double cpu_started = thread_cpu_s();
  const std::optional<std::string> reason = repair(m, nullptr);
  const double cpu_s = thread_cpu_s() - cpu_started;
  const double took_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  if (!reason) {
    // A position report took the batch's changes into the plan first (on its own thread): no
    // repair was left to do here, and the route check above is not one, so it is not sampled.
    ++result.missions_repaired_by_reports;
    return;
  }
  result.mission_replan_cpu_s.push_back(cpu_s);
  result.slowest_replan_s = std::max(result.slowest_replan_s, took_s);
  result.mission_replan_s.push_back(took_s);
  Staged staged;
  if (m.route.edges != before) {
    ++result.routes_changed;
    publish_route(m, *reason, now_s, staged);
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
    // Only while it repairs: between batches the thread serves requests like any other.
    const RealtimeScope realtime(config_.repair_realtime_priority);
    if (config_.repair_realtime_priority > 0) {
      const Realtime now = realtime.granted() ? Realtime::granted : Realtime::denied;
      if (repair_realtime_.exchange(now) != now && now == Realtime::denied) {
        spdlog::warn("event=repair_priority_denied priority={} hint=\"needs root, CAP_SYS_NICE or RLIMIT_RTPRIO; repairs run at normal priority\"",
                     config_.repair_realtime_priority);
      }
    }
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
    result.missions_repaired_by_reports += mine.missions_repaired_by_reports;
    result.slowest_replan_s = std::max(result.slowest_replan_s, mine.slowest_replan_s);
    result.mission_replan_s.insert(result.mission_replan_s.end(), mine.mission_replan_s.begin(), mine.mission_replan_s.end());
    result.mission_replan_cpu_s.insert(result.mission_replan_cpu_s.end(), mine.mission_replan_cpu_s.begin(),
                                       mine.mission_replan_cpu_s.end());
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
      double customization_s = 0;
      repair_plans(apply_changes(expired, "congestion_expired", customization_s), now_s, std::chrono::steady_clock::now(),
                   durable);
    }
  }
  Staged staged;
  {
    std::lock_guard lock(preemption_mutex_);
    signals_.advance(now_s);
    preemption_.tick(now_s);
    if (field_) field_->tick(now_s);
    drain_preemption_events(staged);
    drain_call_records(staged);
    // Recovery ends inside the signals' own clock, without an engine event.
    for (const auto& [node, plan] : signals_map_.signals) announce_signal_state(node, now_s);
    announce_field_states(now_s);
  }
  submit(staged);
}

}  // namespace corridor::server
