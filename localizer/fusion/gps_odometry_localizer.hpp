// The localizer's one entry point per sensor: GPS fixes and odometry increments in, positions on
// the road graph out. As in the seed, GPS is followed while its HDOP is at most 10, through the
// online HMM matcher; when the HDOP is worse or fixes stop coming, odometry takes over from the
// last good fixes and heading and is kept on the map (OdometryMapMatcher). Between two good fixes
// the last one is carried on by the odometry rather than held. The odometry restarts at every
// good fix from where the recent fixes, carried by the odometry, put the vehicle; a fix that
// disagrees with them (multipath) is shown but not restarted from. Handing over to odometry
// continues from there, so the position does not jump beyond the last fix's own error; handing
// back to GPS moves it by the drift the odometry accumulated, which the output's sigma_m said to
// expect.
#pragma once

#include <deque>
#include <optional>

#include "localizer/fusion/odometry_map_matcher.hpp"
#include "localizer/fusion/odometry_scale.hpp"
#include "localizer/match/hmm_matcher.hpp"

namespace corridor::localizer {

struct LocalizerConfig {
  HmmConfig hmm;
  OdometryMatchConfig odometry;
  OdometryScaleConfig odometry_scale;  // the odometry's distances, calibrated by the receiver's speed
  double max_gps_hdop = 10.0;   // the seed's switch
  double gps_timeout_s = 2.5;   // no good fix for this long: odometry...
  // ...or for this many of the receiver's own intervals (the median of its last gaps), if sooner,
  // but not under gps_min_takeover_s: a 1 Hz receiver that misses one fix has gone quiet, and
  // holding its last position for 2.5 s leaves a vehicle at 30 m/s 75 m behind. The floor keeps a
  // fast receiver's latency from handing over between two of its fixes.
  double gps_overdue_intervals = 1.5;
  double gps_min_takeover_s = 1.0;
  double course_memory_m = 300.0;  // a remembered course counts until the odometry has driven this far
  // Along the road, GPS is averaged over the last fixes, each carried forward by the odometry
  // driven since (a stopped vehicle's fixes scatter along its road by σ; their mean by σ/√n).
  std::size_t along_fixes = 10;
  double along_drift_per_m = 0.01;  // the odometry's 1σ per metre carried...
  double along_max_carry_m = 150.0;  // ...and no further than this
  // Where the odometry restarts: the recent fixes, each carried to now by the odometry along the
  // receiver's course, averaged by weight. A carried fix's 1σ is its own, grown by 1 % of the
  // metres carried and by 0.1 m per metre for the course's error (about 6°), so at 10 m/s and
  // 1 Hz about four fixes count, and the mean is some 2× surer than one fix: a parallel road a
  // lane or two away is told apart. Without a course (a receiver that gives none, or none for
  // course_memory_m) a fix cannot be carried once the vehicle moves, and with fewer than two
  // fixes to average the restart is the matched point, as the online match chose it.
  // A fix further than restart_gate_sigmas from the mean (an innovation gate) is shown, with its
  // distance from the mean as its 1σ (unless the odometry has taken over, which then stays the
  // output), but not averaged and not restarted from: a multipath fix 60 m off that the online
  // match followed would otherwise be where the odometry starts if GPS then goes quiet. A gated
  // fix that agrees with the gated fix before it starts the mean afresh: two fixes in a row that
  // agree with each other say the mean was wrong.
  std::size_t restart_fixes = 10;
  double restart_gate_sigmas = 3.0;
  double carry_course_per_m = 0.1;
};

enum class PositionSource { none, gps, odometry };
const char* to_string(PositionSource s);

struct LocalizedPoint {
  PositionSource source = PositionSource::none;
  MatchedPoint match;       // edge, offset and point on the road
  maps::LatLon position;    // of match.point
  double heading_deg = 0;   // of the road there, in the direction of travel
  double speed_mps = 0;
  double sigma_m = 0;       // 1σ accuracy
};

class GpsOdometryLocalizer {
 public:
  GpsOdometryLocalizer(const maps::RoadGraph& graph, const maps::EdgeSnapper& snapper, LocalizerConfig config = {});

  // A GPS fix: followed if its HDOP is at most the limit (none stated counts as good).
  LocalizedPoint on_gps(const GpsFix& fix);
  // An odometry increment: moves the vehicle only while GPS is poor or absent.
  LocalizedPoint on_odometry(const OdometryStep& step);

  [[nodiscard]] const LocalizedPoint& last() const { return last_; }
  // What the odometry's distances are multiplied by (1 until calibrated).
  [[nodiscard]] double odometry_scale() const { return scale_.factor(); }

 private:
  LocalizedPoint output(PositionSource source, const MatchedPoint& m, double sigma_m);
  [[nodiscard]] double road_heading_deg(EdgeId e, double offset_m) const;
  [[nodiscard]] MatchedPoint along_road_mean(const MatchedPoint& m, double sigma_m, double time_s);

  const maps::RoadGraph& graph_;
  LocalizerConfig config_;
  HmmMatcher hmm_;
  OdometryMapMatcher odometry_;
  OdometryScale scale_;
  double last_good_gps_s_ = -1e18;
  double last_fix_s_ = -1e18;  // the last fix of any quality, for the receiver's interval...
  std::deque<double> fix_gaps_;  // ...its last gaps
  [[nodiscard]] double takeover_s() const;  // from fix_gaps_...
  double takeover_s_ = 0;                   // ...as of the last fix
  // The last course over ground seen while moving, turned since by the odometry: a vehicle that
  // stopped keeps facing the way it drove, though the road alone cannot say which way that was.
  std::optional<double> course_deg_;
  double driven_since_course_m_ = 0;
  double odometry_m_ = 0;  // every metre the odometry reported, scale-corrected
  double raw_odometry_m_ = 0;  // the same as reported, for the scale's calibration
  double last_odometry_s_ = -1e18;  // when it last reported
  struct RecentFix {
    EdgeId edge;
    double offset_m = 0;
    double odometry_m = 0;  // odometry_m_ when it came
    double sigma_m = 0;
    double time_s = 0;
  };
  std::deque<RecentFix> recent_;
  // A fix in the local frame with its 1σ, and the dead reckoning since.
  struct CarriedFix {
    maps::Point2 point;
    double sigma_m = 0;
    double driven_m = 0;
    maps::Point2 moved;       // along the course...
    bool course_known = true;  // ...when it was known all the way
  };
  struct FixMean {
    bool valid = false;
    maps::Point2 point;
    double sigma_m = 0;
  };
  std::deque<CarriedFix> carried_;   // the fixes the odometry restarts from, oldest first
  std::optional<CarriedFix> gated_;  // the last fix, if it failed the gate
  [[nodiscard]] FixMean fix_mean() const;  // valid when at least two fixes count
  [[nodiscard]] bool agrees(const FixMean& mean, maps::Point2 fix, double sigma_m) const;
  [[nodiscard]] FixMean carried_to_now(const CarriedFix& f) const;
  static void dead_reckon(CarriedFix& f, double distance_m, std::optional<double> course_deg);
  LocalizedPoint last_;
};

}  // namespace corridor::localizer
