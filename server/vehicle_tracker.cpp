#include "server/vehicle_tracker.hpp"

#include <cmath>

namespace corridor::server {

const char* to_string(Disposition d) {
  switch (d) {
    case Disposition::followed: return "followed";
    case Disposition::stale: return "stale";
    case Disposition::duplicate: return "duplicate";
    case Disposition::outlier: return "outlier";
    case Disposition::low_accuracy: return "low_accuracy";
  }
  return "followed";
}

struct VehicleTracker::Vehicle {
  std::mutex mutex;
  localizer::HmmMatcher matcher;
  std::optional<double> last_time_s;
  maps::Point2 last_raw;
  int outliers_in_row = 0;

  Vehicle(const maps::RoadGraph& g, const maps::EdgeSnapper& s, const localizer::HmmConfig& c)
      : matcher(g, s, c, localizer::SearchArrays::lent) {}
};

VehicleTracker::VehicleTracker(const maps::RoadGraph& graph, const maps::EdgeSnapper& snapper, TrackerConfig config)
    : graph_(graph), snapper_(snapper), config_(config) {
  config_.matcher.validate();
}

VehicleTracker::~VehicleTracker() = default;

VehicleTracker::Vehicle& VehicleTracker::vehicle(const std::string& id) {
  {
    std::shared_lock lock(mutex_);
    if (auto it = vehicles_.find(id); it != vehicles_.end()) return *it->second;
  }
  std::lock_guard lock(mutex_);
  auto& slot = vehicles_[id];
  if (!slot) slot = std::make_unique<Vehicle>(graph_, snapper_, config_.matcher);
  return *slot;
}

TrackResult VehicleTracker::track(const PositionReport& p) {
  TrackResult r;
  const bool vo = p.source == "vo";
  if (!vo && p.hdop && *p.hdop > config_.max_gps_hdop) {
    r.disposition = Disposition::low_accuracy;
    return r;
  }
  Vehicle& v = vehicle(p.vehicle_id);
  std::lock_guard lock(v.mutex);
  const maps::Point2 raw = graph_.projection().to_local(p.position);
  if (v.last_time_s) {
    if (p.timestamp_s < *v.last_time_s) {
      r.disposition = Disposition::stale;
      return r;
    }
    const double moved = maps::distance_m(raw, v.last_raw);
    if (p.timestamp_s == *v.last_time_s) {
      r.disposition = moved < 0.5 ? Disposition::duplicate : Disposition::stale;
      return r;
    }
    const double dt = p.timestamp_s - *v.last_time_s;
    if (moved > config_.jump_slack_m && moved / dt > config_.max_speed_mps &&
        ++v.outliers_in_row < config_.outliers_before_reset) {
      r.disposition = Disposition::outlier;
      return r;
    }
    if (v.outliers_in_row >= config_.outliers_before_reset) v.matcher.reset();  // it really moved
  }
  v.outliers_in_row = 0;
  v.last_time_s = p.timestamp_s;
  v.last_raw = raw;
  localizer::GpsFix fix;
  fix.time_s = p.timestamp_s;
  fix.position = p.position;
  fix.hdop = p.hdop ? p.hdop : (vo ? std::optional<double>(config_.vo_hdop) : std::nullopt);
  fix.heading_deg = p.heading_deg;
  fix.speed_mps = p.speed_mps;
  // The search arrays are per thread, not per vehicle: a graph-sized set for each of hundreds of
  // vehicles would cost more memory than the rest of the server.
  thread_local std::unique_ptr<planner::BoundedDistances> arrays;
  if (!arrays || arrays->node_count() != graph_.node_count()) arrays = std::make_unique<planner::BoundedDistances>(graph_.node_count());
  r.match = v.matcher.update(fix, arrays.get());
  return r;
}

}  // namespace corridor::server
