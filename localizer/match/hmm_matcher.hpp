// Online and batch HMM map matching (Newson & Krumm 2009) on the road graph. Candidates are road
// points within a radius (the snapper's R-tree); the emission is Gaussian in the distance to the
// road, with σ = HDOP × a base; the transition compares the network distance between consecutive
// candidates (the planner's bounded one-to-many search) with the straight-line distance between
// the fixes. Heading and speed, when a fix has them, weigh candidates and moves. Viterbi runs
// incrementally, keeping a bounded window; a time gap, no candidate, or no possible move breaks
// the chain, which restarts cleanly at the next fix, and a candidate that no move explains (the
// vehicle drove where the map has no road) may start it afresh, at a price. In batch, a few fixes
// in a row may instead be set aside as outliers (max_skipped), where the fixes after them fit the
// chain; a time gap, or more than that, still breaks it.
#pragma once

#include <cstdint>
#include <deque>
#include <memory>
#include <span>
#include <vector>

#include "localizer/match/gps_fix.hpp"
#include "localizer/match/path_smoother.hpp"
#include "maps/edge_snapper.hpp"
#include "planner/bounded_search.hpp"

namespace corridor::localizer {

struct HmmConfig {
  double sigma_base_m = 4.0;      // σ of the emission = HDOP × this (Newson & Krumm: 4.07 m)
  double default_hdop = 1.5;      // for fixes without HDOP
  double min_radius_m = 30.0;     // candidates within max(this, radius_sigmas × σ)
  double radius_sigmas = 4.0;
  double max_radius_m = 200.0;
  // Roads per fix (each two-way road gives two directed points). The disc grows to 4σ: at σ 15 m,
  // 60 m, and in an old town more than six roads lie that close, so the driven one could be left
  // out of a noisy fix's candidates. Ten cost about 3 % of batch throughput
  // (docs/experiments/localization.md).
  std::size_t max_candidates = 10;
  double beta_m = 6.0;            // transition scale for |network − straight-line| (metres)...
  double beta_per_sigma = 0.7;    // ...at least this × the fix's σ
  double max_speed_mps = 70.0;    // a move needing more is impossible
  // Fixes further apart in time break the chain. A GPS outage of a few minutes (a tunnel) is
  // linked across: the route through it is checked against the straight line.
  double gap_s = 180.0;
  // One fix's speed × the time since the last fix measures the distance driven over the interval
  // of a tracker's feed (up to this), not over a longer gap (a tunnel), in which the vehicle may
  // have stopped or sped up meanwhile.
  double speed_gap_s = 30.0;
  // The course over ground of a moving fix, against the road's bearing: a mixture of two
  // Gaussians. Along a road the course follows its bearing to within the receiver's course error,
  // a lane change and the road's drawing (heading_sigma_deg); through a junction's turn, or where
  // a road is drawn coarsely, it sweeps far from it (heading_wide_sigma_deg, a share
  // heading_wide_share of the fixes). One Gaussian wide enough for the turns (40°) tells a road
  // from a neighbour 30° off by only 0.3 (log-likelihood), and one narrow enough for that would
  // price every turn as an error (see docs/experiments/localization.md, The course as a mixture).
  double heading_sigma_deg = 10.0;
  double heading_wide_sigma_deg = 40.0;
  double heading_wide_share = 0.2;
  double heading_min_speed_mps = 2.0;  // below this the course over ground is noise
  // Noise may put a fix a little behind the last one on the same road: up to the larger of these
  // is read as standing or creeping, not as a drive round the block. Two fixes' positions along a
  // road differ by noise of σ√2, so 3σ lets through nearly all of it while the vehicle stands.
  double backward_tolerance_m = 8.0;
  double backward_sigmas = 3.0;
  // A move straight back onto the road it came by (a U-turn at the node): rare in traffic, yet as
  // cheap as standing still where a stopped vehicle's fixes scatter across a junction. Its price,
  // as a log-likelihood.
  double uturn_penalty = 4.0;
  // A move from a through road onto a service road (a car park's aisle, a bypass drawn a few
  // metres beside its street) pays this (a log-likelihood, about a 1.4σ emission): where the fixes
  // fit both alike, the through road is the likelier drive; where they leave for the service
  // road, they outweigh it within a fix or two. Measured on drives that use service roads too
  // (docs/experiments/localization.md).
  double service_entry_penalty = 1.0;
  std::size_t window = 8;         // online: steps kept (the lag bound)
  // Batch: fixes in a row that may be set aside as outliers (multipath) before the chain breaks
  // (at most 16). A fix nothing reaches, or with no road near, is set aside outright; any other
  // fix may be, if the path round it scores better by more than outlier_penalty (a
  // log-likelihood: about the price of a 3.5σ emission) for each fix it leaves out. Set-aside
  // fixes between a chain's matched ones are flagged, and placed on the path by the smoother
  // (unless along_path is projected, when they stay unmatched).
  std::size_t max_skipped = 2;
  double outlier_penalty = 6.0;
  // A fix's candidate may also start the chain afresh, at this price (a log-likelihood), where every
  // move into it from the last fix scores worse, or none reaches it while another candidate is
  // reached. A vehicle on a road the map lacks (a street closed to traffic that it drives anyway,
  // a car park) has fixes that no mapped move explains; without a way to start afresh, the chain
  // stays on the roads that stay reachable, priced only by their emissions, and glues the matched
  // path to a wrong road for as long as the vehicle is off the map. 40 is beyond any move a road
  // explains (|route − driven| of about 40 β); the figures in docs/experiments/localization.md
  // hold from 30 to 70. Infinite: never.
  double restart_penalty = 40.0;
  // Batch: smooth each chain along its matched path (path_smoother.hpp), or leave each point
  // where its fix projects.
  enum class AlongPath { smoothed, projected } along_path = AlongPath::smoothed;

  // Throws std::invalid_argument for a non-positive scale or radius.
  void validate() const;
};

// Whether a matcher owns the arrays of its network-distance searches (one per node of the graph),
// or borrows them for each call: a server tracking hundreds of vehicles lends one set per thread
// instead of keeping a graph-sized set per vehicle.
enum class SearchArrays { owned, lent };

class HmmMatcher {
 public:
  HmmMatcher(const maps::RoadGraph& graph, const maps::EdgeSnapper& snapper, HmmConfig config = {},
             SearchArrays arrays = SearchArrays::owned);

  // Online: takes the next fix (time not before the last one's) and returns the best estimate of
  // where the vehicle is now, given every fix so far in the chain. A matcher with lent arrays
  // must be given them here; an owning one may be.
  MatchedPoint update(const GpsFix& fix, planner::BoundedDistances* lent = nullptr);
  // Forgets the chain (a vehicle teleported, a new trace).
  void reset();

  // Batch: the most likely sequence through a whole trace, one point per fix (breaks included).
  // Throws std::invalid_argument when times decrease or a fix is not a finite coordinate.
  std::vector<MatchedPoint> match(std::span<const GpsFix> trace);

  [[nodiscard]] const HmmConfig& config() const { return config_; }

 private:
  struct Candidate {
    EdgeId edge;
    double offset_m;
    maps::Point2 point;
    double distance_m;
    double score;         // log probability of the best path ending here
    std::int32_t parent;  // index in the step `back` steps earlier, -1 at a chain start or a restart
    std::uint8_t back = 1;  // batch: more than 1 where the best path sets fixes aside as outliers
    bool restart = false;   // the best path into it starts afresh here (restart_penalty)
    std::uint32_t chain = 0;  // online: which unbroken path it is on (new at each break or restart)
  };
  struct Step {
    double time_s;
    maps::Point2 raw;
    std::vector<Candidate> candidates;
    bool chain_start = false;
    // Candidates' scores are kept near zero; a score plus its step's `norm` is the log probability
    // on the chain's common scale, which skip arcs over several steps compare.
    double norm = 0.0;
  };

  // The heading term of the emission (log-likelihood, 0 at 0°) for an angle between the fix's
  // course and the road's bearing.
  [[nodiscard]] double heading_log_likelihood(double angle_deg) const;
  // Candidates of a fix with their emission scores.
  std::vector<Candidate> candidates_for(const GpsFix& fix, maps::Point2 raw) const;
  // The best move found so far into each candidate of a step, and the nodes the moves' searches
  // must settle (its candidates' edge tails, once for every earlier step they are relaxed from).
  struct Links {
    Links(const maps::RoadGraph& graph, const std::vector<Candidate>& next);
    std::vector<double> best;
    std::vector<std::int32_t> parent;  // as Candidate::parent, or kRestart where it starts afresh
    std::vector<std::uint8_t> back;
    std::vector<NodeId> targets;
  };
  // Every move from `prev`'s candidates to `next`'s, each scored less `penalty`, kept in `links`
  // where it beats the best so far. Scores in `links` are on the scale of the step whose norm is
  // `base`.
  void relax(const Step& prev, const Step& next, const GpsFix& fix, double penalty, std::uint8_t back, double base,
             planner::BoundedDistances& distances, Links& links) const;
  // Lets each candidate of `links` start afresh at restart_penalty where every move into it scores
  // worse (scores on the scale of the last step's).
  void allow_restarts(Links& links) const;
  // Gives `next` the scores and parents of `links` (on the scale of `base`); false (and `next`
  // untouched) when no candidate was reached.
  static bool apply(Step& next, const Links& links, double base);
  // Links `next` to `prev` (scores and parents); false when no candidate can be reached.
  bool link(const Step& prev, Step& next, const GpsFix& fix, planner::BoundedDistances& distances);
  [[nodiscard]] MatchedPoint point_of(const Step& step, std::size_t index) const;
  [[nodiscard]] static std::size_t best(const Step& step);

  const maps::RoadGraph& graph_;
  const maps::EdgeSnapper& snapper_;
  HmmConfig config_;
  std::unique_ptr<planner::BoundedDistances> distances_;  // null when lent
  // The heading mixture's parts' log weights (log(share / σ)) and its log density at 0°, fixed by
  // the configuration: worked out once, not for every candidate.
  double heading_log_narrow_ = 0, heading_log_wide_ = 0, heading_log_at_zero_ = 0;
  std::deque<Step> window_;
  // Online: the path of the last point reported, and the next path's number. A best candidate on
  // another path than the last one reported is a jump with no route between: a chain start.
  std::uint32_t reported_chain_ = 0, next_chain_ = 1;
};

}  // namespace corridor::localizer
