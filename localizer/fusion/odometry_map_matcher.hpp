// Odometry map matching for when GPS is poor or absent (Parra Alonso et al., the seed paper
// 001_25af06b4c534220d, §IV), kept as several hypotheses on the road graph instead of one.
//
// Relative motion (distance driven, heading change) is integrated in the graph's local metric
// frame from the last good fix: a dead-reckoned curve. Each hypothesis is a place on the road that
// the vehicle may have reached by driving that distance from one of the start candidates (the §IV
// confidence region around the last good fix), with the curve turned to fit its start road. Its
// start pays for its distance from the fix and for that turn against the fix's heading (whose 1σ
// is wide when only a road's bearing gave it: a vehicle that was stopped may face either way). A
// hypothesis branches into every exit at a junction, and pays per metre for how far its road
// departs from the odometry:
// - the curve-to-curve term: the angle between its road and the odometry's heading there;
// - the point-to-curve term: its distance from its dead-reckoned position, against a 1σ that grows
//   with the distance driven since its last reset.
// Hypotheses far behind the best are pruned; equal places merge. One wrong committed exit at a
// fork of two near-parallel streets no longer costs the whole outage: the other branch lives until
// the streets part.
//
// §IV's tracking rules, per hypothesis: the 1σ grows with the distance driven; a heading that
// disagrees with the road by more than 20° over the last 5 s raises it by 20%; a turn sharper than
// 50° at a junction where the odometry turned too is a known place, so the along-road drift resets
// there, and the hypothesis is moved along its road to where the odometry's turn was.
#pragma once

#include <deque>
#include <optional>
#include <vector>

#include "localizer/match/corner_cut.hpp"
#include "localizer/match/gps_fix.hpp"
#include "maps/edge_snapper.hpp"
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
  double reset_turn_deg = 50.0;      // a turn sharper than this resets the drift to the map
  double turn_window_m = 40.0;       // the odometry's turn is looked for from this far before a sharp junction, once half as far past it

  // The hypotheses.
  std::size_t max_hypotheses = 24;
  double start_radius_m = 25.0;      // start candidates within max(this, 2σ of the last fix)
  double heading_sigma_deg = 15.0;   // curve to curve: cost (angle/σ)²/2 per 10 m...
  double heading_cap_deg = 60.0;     // ...the angle capped here (a turn's lag costs both branches alike)
  double position_base_m = 5.0;      // point to curve: 1σ of the dead-reckoned position at the start...
  double position_drift_per_m = 0.03;  // ...growing this much per metre driven
  double position_cap = 8.0;         // per 10 m, so one bad stretch cannot outweigh the heading
  double prune_margin = 25.0;        // cost behind the best beyond which a hypothesis is dropped
  // Each hypothesis slowly aligns the odometry with its road (a complementary filter): the heading
  // over this many metres of straight road, the dead-reckoned position over that many. The start's
  // heading can be off by a GPS course's error, and 15° puts the curve on the parallel street
  // after 80 m; the slow position pull keeps the point-to-curve term about the recent drive.
  double heading_align_m = 50.0;
  double position_align_m = 300.0;
  // The along-road drift between sharp turns (a scale error, a road drawn shorter than driven):
  // every so many metres the best hypotheses put out siblings a few metres ahead and behind, and
  // the road's bends pick the one that fits.
  double sibling_every_m = 20.0;
  double sibling_step_m = 3.0;
  double sibling_cost = 1.0;
  std::size_t sibling_parents = 3;
  double merge_m = 2.0;              // two hypotheses this close on one edge are one
  // A slow vehicle (odometry under slow_speed_mps: slowing for a junction, or stopping) takes a
  // junction's exits only once it is junction_commit_m past the node; until then it waits at its
  // approach's end, the distance carried, not lost. Stopped at a stop line right by the node, a
  // few decimetres of drift would otherwise put it on an exit, past the signal it is waiting at.
  // A faster vehicle commits at once: holding it back makes it lag at every junction (measured:
  // docs/experiments/localization.md).
  double junction_commit_m = 2.0;
  double slow_speed_mps = 4.0;
  // Through a junction the odometry measures the arc driven, the hypotheses move along the centre
  // lines (corner_cut.hpp; radius 0 and offset 0: the centre lines).
  CornerModel corner;
};

// Where the odometry starts: the last good fix, matched.
struct OdometryStart {
  EdgeId edge;              // the matched edge...
  double offset_m = 0;      // ...and offset
  maps::Point2 point;       // the dead reckoning's origin: the matched point, or where the recent
                            // fixes put the vehicle (then the matched edge pays for its distance)
  double heading_deg = 0;   // the vehicle's heading there...
  double heading_sigma_deg = 20.0;  // ...and its 1σ (a receiver's course: small; a road's bearing alone: large)
  double time_s = 0;
  double sigma_m = 5.0;     // 1σ of the fix
};

class OdometryMapMatcher {
 public:
  // The snapper finds the start candidates around the last good fix; without one, only the
  // matched edge (and its twin) start.
  explicit OdometryMapMatcher(const maps::RoadGraph& graph, OdometryMatchConfig config = {},
                              const maps::EdgeSnapper* snapper = nullptr);

  // Starts from a point on the road (a matched GPS fix) with the vehicle's heading there. Cheap:
  // the hypotheses are made when the odometry is first advanced.
  void start(const OdometryStart& from);
  void start(EdgeId edge, double offset_m, double heading_deg, double time_s, double sigma_m);
  [[nodiscard]] bool started() const { return start_.edge.valid(); }

  // Records an increment while GPS is still followed: before the hypotheses exist it is only
  // kept, and they are made and driven through every kept increment when advance() is first
  // called; once they exist, it advances them.
  void record(const OdometryStep& step);
  // Advances by one increment and returns the best hypothesis's position (unmatched if not started).
  MatchedPoint advance(const OdometryStep& step);
  // A poor fix (HDOP over the switch's limit) still weighs the hypotheses, with its own large 1σ.
  void observe(maps::Point2 fix, double sigma_m);

  [[nodiscard]] double sigma_m() const;
  [[nodiscard]] double heading_deg() const { return heading_deg_; }
  [[nodiscard]] std::size_t resets() const;
  [[nodiscard]] std::size_t hypotheses() const { return hyps_.size(); }

 private:
  struct Hypothesis {
    EdgeId edge;
    double offset_m = 0;
    double cost = 0;
    double sigma_m = 0;
    // The odometry's frame as this hypothesis sees it: the heading offset that aligned the vehicle
    // with its start road, and the dead-reckoned position from where its drift was last reset.
    double heading_bias_deg = 0;
    maps::Point2 reckoned;
    double reckoned_from_m = 0;
    double last_raise_s = -1e18;
    std::size_t resets = 0;
    // The odometry distance at the last node passed; and the last sharp turn of the road at a
    // node, with its distance and angle, until the drift reset has checked it (another node
    // soon after, where two ways meet, must not take its place).
    double junction_s = -1e18;
    double sharp_s = -1e18;
    double sharp_turn_deg = 0;
    bool sharp_pending = false;
    // Waiting at its approach's end: how far past the node the odometry has carried it while
    // slow (added to the next move).
    double past_node_m = 0;
  };
  struct Pending {
    OdometryStep step;
    std::optional<maps::Point2> fix;
    double fix_sigma_m = 0;
  };

  [[nodiscard]] double road_bearing_deg(EdgeId e, double offset_m) const;
  void seed();
  void drive(double distance_m, double turn_deg);
  void move(Hypothesis h, double left_m, std::vector<Hypothesis>& out) const;
  void score(double distance_m);
  void reset_at_turns();
  void heading_check(double time_s);
  void prune();
  bool add_siblings();  // whether any were added
  [[nodiscard]] MatchedPoint current() const;
  [[nodiscard]] double heading_at(double s) const;

  const maps::RoadGraph& graph_;
  OdometryMatchConfig config_;
  const maps::EdgeSnapper* snapper_;
  OdometryStart start_;
  std::vector<Pending> pending_;
  std::vector<Hypothesis> hyps_;
  std::vector<Hypothesis> scratch_;
  bool seeded_ = false;
  bool slow_ = false;       // the last increment was slower than slow_speed_mps
  double heading_deg_ = 0;  // integrated odometry heading from the start's (a hypothesis adds its bias)
  double driven_m_ = 0;     // since the start
  double siblings_at_m_ = 0;
  std::deque<std::pair<double, double>> headings_;  // (time, heading) over the heading window
  std::deque<std::pair<double, double>> track_;     // (driven, heading) over the turn window
};

}  // namespace corridor::localizer
