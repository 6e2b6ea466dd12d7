// Odometry map matching for when GPS is poor or absent (Parra Alonso et al., the seed paper
// 001_25af06b4c534220d, §IV): relative motion (distance driven, heading change) is integrated in
// the graph's local metric frame from the last good fix and its heading, and kept on the road:
// the vehicle advances along its edge, and at a junction the turn-or-straight decision compares
// the odometry's heading with each exit's bearing over the first metres past the junction (a
// short curve-to-curve match). The uncertainty grows with distance; a heading that disagrees with
// the road by more than 20° raises it by 20%; a turn sharper than 50° resets it to the map, since
// the junction where the turn happened is a known place.
#pragma once

#include <deque>
#include <vector>

#include "localizer/match/gps_fix.hpp"
#include "maps/road_graph.hpp"

namespace corridor::localizer {

// One relative-motion increment, as a visual or wheel odometry reports it between two instants.
struct OdometryStep {
  double time_s = 0;              // at the end of the increment
  double distance_m = 0;          // driven during it, ≥ 0
  double heading_change_deg = 0;  // clockwise positive
};

struct OdometryMatchConfig {
  double drift_per_m = 0.01;         // 1σ growth of the along-road error per metre driven
  double base_sigma_m = 3.0;         // uncertainty right after a reset
  double disagreement_deg = 20.0;    // heading vs road beyond this raises the uncertainty...
  double disagreement_raise = 1.2;   // ...by this factor (once per second of disagreement)
  double heading_window_s = 5.0;     // the heading check looks this far back
  double decision_m = 20.0;          // a junction's exit is decided over this many metres past it
  double reset_turn_deg = 50.0;      // a turn sharper than this resets the drift to the map
};

class OdometryMapMatcher {
 public:
  OdometryMapMatcher(const maps::RoadGraph& graph, OdometryMatchConfig config = {});

  // Starts from a point on the road (a matched GPS fix) with the vehicle's heading there.
  void start(EdgeId edge, double offset_m, double heading_deg, double time_s, double sigma_m);
  [[nodiscard]] bool started() const { return edge_.valid(); }

  // Advances by one increment and returns the map-constrained position (unmatched if not started).
  MatchedPoint advance(const OdometryStep& step);

  [[nodiscard]] double sigma_m() const { return sigma_m_; }
  [[nodiscard]] double heading_deg() const { return heading_deg_; }
  [[nodiscard]] std::size_t resets() const { return resets_; }

 private:
  [[nodiscard]] double road_bearing_deg(EdgeId e, double offset_m) const;
  [[nodiscard]] MatchedPoint current() const;
  void decide_exit();

  const maps::RoadGraph& graph_;
  OdometryMatchConfig config_;
  EdgeId edge_;
  double offset_m_ = 0;
  double heading_deg_ = 0;  // integrated odometry heading in the map frame
  double sigma_m_ = 0;
  double last_time_s_ = 0;
  double last_raise_s_ = -1e18;
  std::size_t resets_ = 0;
  // A junction passed within decision_m: the exits still in play and the edge we came from.
  std::vector<EdgeId> exits_;
  EdgeId came_from_;
  double past_junction_m_ = 0;
  double heading_at_junction_deg_ = 0;
  std::deque<std::pair<double, double>> headings_;  // (time, heading) over the heading window
};

}  // namespace corridor::localizer
