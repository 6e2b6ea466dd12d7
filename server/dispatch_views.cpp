// What the dispatch service shows of itself: vehicles, missions and a mission's route revisions, as
// the API returns them.
#include "planner/route_geojson.hpp"
#include "server/dispatch_mission.hpp"
#include "server/dispatch_service.hpp"

namespace corridor::server {

std::vector<VehicleView> DispatchService::vehicles() const {
  std::vector<VehicleView> out;
  std::shared_lock lock(registry_mutex_);
  out.reserve(vehicles_.size());
  for (const auto& [id, v] : vehicles_) {
    out.push_back(v);
    if (auto it = active_by_vehicle_.find(id); it != active_by_vehicle_.end()) out.back().mission = it->second;
  }
  std::sort(out.begin(), out.end(), [](const VehicleView& a, const VehicleView& b) { return a.vehicle_id < b.vehicle_id; });
  return out;
}

std::vector<RouteRevisionView> DispatchService::route_history(MissionId id) const {
  MissionPtr m;
  {
    std::shared_lock lock(registry_mutex_);
    auto it = missions_.find(id);
    if (it == missions_.end()) throw not_found("no mission " + std::to_string(id));
    m = it->second;
  }
  std::vector<Mission::Revision> history;
  {
    std::lock_guard lock(m->mutex);
    history = m->history;
  }
  // Rendered outside the mission's lock: the routes are copies.
  std::vector<RouteRevisionView> out;
  out.reserve(history.size());
  for (auto& r : history) {
    if (r.view.geometry_json.empty() && r.route) {
      r.view.geometry_json = planner::route_to_geojson(graph_, *r.route, "dstar")["geometry"].dump();
    }
    out.push_back(std::move(r.view));
  }
  return out;
}

MissionView DispatchService::view(const Mission& m) const {
  MissionView v;
  v.id = m.row.id;
  v.vehicle_id = m.row.vehicle_id;
  v.state = m.row.state;
  v.priority = m.row.priority;
  v.vmax_kmh = m.row.vmax_kmh;
  v.profile = m.row.profile;
  v.destination = m.row.destination;
  v.last_position = m.last_position;
  v.route = m.route;
  v.route_revision = m.revision;
  v.route_time_s = m.route_time_s;
  if (m.row.state == MissionState::active) {
    {
      std::shared_lock costs(overlay_mutex_);
      v.congestion_factors.reserve(m.route.edges.size());
      for (EdgeId e : m.route.edges) v.congestion_factors.push_back(overlay_.edge(e).congestion_factor);
    }
    std::lock_guard lock(preemption_mutex_);
    v.schedule = preemption_.schedule(m.row.id);
  } else {
    v.schedule = m.final_schedule;
  }
  v.created_s = m.row.created_s;
  v.updated_s = m.row.updated_s;
  return v;
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

}  // namespace corridor::server
