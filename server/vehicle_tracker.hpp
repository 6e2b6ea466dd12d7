// Where each vehicle is: its own online map matcher and its last accepted fix. Decides whether a
// report moves the vehicle (followed) or is only stored: older than the last accepted one (stale),
// the same again (duplicate), a jump faster than any vehicle drives (outlier), or GPS too poor to
// follow (HDOP over 10: as in the seed, the vehicle's own odometry, source "vo", takes over).
// Thread-safe, with one lock per vehicle, taken alone: never while a service lock is held.
#pragma once

#include <memory>
#include <mutex>
#include <optional>
#include <shared_mutex>
#include <string>
#include <unordered_map>

#include "localizer/match/hmm_matcher.hpp"
#include "server/dispatch_types.hpp"

namespace corridor::server {

struct TrackerConfig {
  localizer::HmmConfig matcher;
  double max_speed_mps = 70.0;   // a jump faster than this from the last accepted fix is an outlier,
  double jump_slack_m = 60.0;    // once it is more than this (GPS noise) away
  int outliers_before_reset = 3;  // that many in a row: the vehicle really is there; restart the chain
  double max_gps_hdop = 10.0;    // GPS worse than this is stored, not followed
  double vo_hdop = 2.0;          // a source "vo" position without HDOP is weighed as this
};

enum class Disposition { followed, stale, duplicate, outlier, low_accuracy };
const char* to_string(Disposition d);

struct TrackResult {
  Disposition disposition = Disposition::followed;
  localizer::MatchedPoint match;  // when followed: where the matcher puts the vehicle (may be unmatched)
};

class VehicleTracker {
 public:
  VehicleTracker(const maps::RoadGraph& graph, const maps::EdgeSnapper& snapper, TrackerConfig config = {});
  ~VehicleTracker();

  // The report's fate and, when followed, its match. The report must already be validated.
  TrackResult track(const PositionReport& report);

 private:
  struct Vehicle;
  Vehicle& vehicle(const std::string& id);

  const maps::RoadGraph& graph_;
  const maps::EdgeSnapper& snapper_;
  TrackerConfig config_;
  std::shared_mutex mutex_;  // guards the map; each vehicle has its own lock
  std::unordered_map<std::string, std::unique_ptr<Vehicle>> vehicles_;
};

}  // namespace corridor::server
