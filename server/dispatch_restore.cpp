// The dispatch service's start from its store: congestion still in force, every vehicle's latest
// position, and the missions, the active ones planned again from where their vehicles last were.
#include "server/dispatch_service.hpp"

#include <spdlog/spdlog.h>

#include "maps/errors.hpp"
#include "server/dispatch_mission.hpp"

namespace corridor::server {

// Runs in the constructor, before the service is shared: no locks needed.
void DispatchService::restore(double now_s) {
  const auto restored_history = [this](MissionId id) {
    std::vector<Mission::Revision> out;
    for (RouteRevisionView& v : store_->route_revisions(id)) out.push_back({std::move(v), std::nullopt});
    return out;
  };
  for (const CongestionRow& c : store_->congestion_in_force(now_s)) {
    if (c.edge.index() >= graph_.edge_count()) continue;  // recorded against another map
    overlay_.set_edge(c.edge, c.condition);
    const std::uint64_t seq = ++update_sequence_;
    latest_update_[c.edge] = seq;
    if (c.expires_at_s) expiries_.emplace(*c.expires_at_s, std::make_pair(c.edge, seq));
  }
  Staged staged;
  // Every vehicle where it last reported, as it reported it (source and speed too), with or
  // without a mission.
  std::unordered_map<std::string, PositionRow> last_by_vehicle;
  for (PositionRow& last : store_->last_positions()) {
    vehicles_[last.vehicle_id] = {last.vehicle_id, last.position, last.heading_deg, last.speed_mps,
                                  last.timestamp_s,  last.source,   std::nullopt};
    std::string id = last.vehicle_id;
    last_by_vehicle.emplace(std::move(id), std::move(last));
  }
  for (MissionRow row : store_->missions(std::nullopt)) {
    next_mission_id_ = std::max(next_mission_id_, row.id + 1);
    if (row.profile != "ambulance" && row.profile != "fire_engine") {
      // Written by a later version: plan, and say, what this build knows.
      spdlog::warn("event=mission_profile_unknown mission={} profile={} planned_as=ambulance", row.id, row.profile);
      row.profile = "ambulance";
    }
    const auto found = last_by_vehicle.find(row.vehicle_id);
    const std::optional<PositionRow> last =
        found == last_by_vehicle.end() ? std::nullopt : std::optional<PositionRow>(found->second);
    if (row.state != MissionState::active) {
      // Finished missions stay readable; they need no planner.
      auto m = std::make_shared<Mission>();
      m->row = row;
      if (last) m->last_position = last->position;
      m->history = restored_history(row.id);
      m->revision = m->history.empty() ? 0 : m->history.back().view.revision;
      missions_[row.id] = std::move(m);
      continue;
    }
    const maps::LatLon start = last ? last->position : row.origin.value_or(row.destination);
    try {
      auto from = snapper_.snap(start, trip_end_snap(last.has_value()));
      auto to = snapper_.snap(row.destination, trip_end_snap(false));
      auto m = std::make_shared<Mission>();
      m->row = row;
      m->last_position = start;
      plan_mission(*m, start, from, to, last ? last->heading_deg : std::nullopt);
      m->route_time_s = now_s;
      m->history = restored_history(row.id);
      m->revision = m->history.empty() ? 0 : m->history.back().view.revision;
      missions_[row.id] = m;
      active_by_vehicle_[row.vehicle_id] = row.id;
      publish_route(*m, "restart", now_s, staged);
      spdlog::info("event=mission_resumed mission={} vehicle={}", row.id, row.vehicle_id);
    } catch (const maps::SnapError& e) {
      spdlog::error("event=mission_not_resumable mission={} reason=\"{}\"", row.id, e.what());
    }
  }
  submit(staged)->wait();
}

}  // namespace corridor::server
