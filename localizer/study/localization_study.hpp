// The localization accuracy study: SUMO's own trajectories (fcd) as ground truth, turned into
// noisy GPS with multipath outliers and an outage, and into odometry with the drift we measured on
// our stereo VO; then matched three ways (nearest road, HMM over GPS alone, GPS/odometry fusion)
// and scored against the truth: RMSE, correct edge by time and by length, and how the fusion holds
// the road through the outage and recovers after it.
#pragma once

#include <algorithm>

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "localizer/fusion/gps_odometry_localizer.hpp"
#include "localizer/fusion/simulated_odometry.hpp"
#include "localizer/match/fcd_trace.hpp"

namespace corridor::localizer {

struct StudyConfig {
  double noise_sigma_m = 8.0;       // GPS noise, per axis
  double outlier_share = 0.02;      // multipath: fixes thrown 40–100 m
  double outage_s = 60.0;           // one GPS outage per drive (0: none)...
  double outage_at = 0.4;           // ...starting this far into the drive
  VoDriftModel odometry;
  double truth_radius_m = 20.0;     // the true edge is searched this close to the true position
  std::uint64_t seed = 1;
  LocalizerConfig localizer;
};

struct DriveResult {
  std::string id;
  std::size_t samples = 0;
  double length_m = 0;
  // Squared-error sums and counts, so drives add up.
  double sq_raw = 0, sq_nearest = 0, sq_hmm = 0, sq_fused = 0;
  std::size_t n_raw = 0, n_hmm = 0, n_fused = 0;
  std::size_t with_truth = 0;
  // The HMM's squared errors again, over the samples with a true edge only. A sample has none
  // where no road of our graph within truth_radius_m runs the vehicle's way: mostly SUMO is then
  // driving a road our importer leaves out (a way tagged `construction`, which netconvert
  // keeps), where no matcher on our graph can place the vehicle.
  double sq_hmm_on_graph = 0;
  std::size_t n_hmm_on_graph = 0;
  std::size_t correct_nearest_road = 0, correct_hmm = 0, correct_hmm_road = 0, correct_fused = 0;
  double length_with_truth = 0, length_correct_hmm = 0;
  // The outage.
  std::size_t outage_samples = 0, outage_correct = 0;
  // The same shares judged by the nearest-road oracle alone (true_edge below), over the samples
  // it has a truth for, for comparison.
  std::size_t with_truth_nearest_oracle = 0, correct_hmm_nearest_oracle = 0;
  std::size_t outage_samples_nearest_oracle = 0, outage_correct_nearest_oracle = 0;
  std::size_t truth_from_lane = 0;  // samples whose true edge the lane's way chose (junctions apart)
  double outage_sq = 0;
  double recovery_s = 0;    // after the outage: until the fused estimate is on the true edge again
  double handback_jump_m = 0;  // how far the position moved when GPS came back
  // The odometry's scale error when the outage begins, as simulated and after the fusion's
  // calibration against the receiver's speed: squared sums over drives with an outage.
  double scale_sq_raw = 0, scale_sq_calibrated = 0;
  std::size_t scale_n = 0;
};

struct StudyResult {
  std::vector<DriveResult> drives;
  DriveResult total;  // sums over every drive (id "all")
};

// Every vehicle's trajectory is one drive. `trace_of` (optional) receives, for one vehicle id,
// the per-sample truth, raw GPS, HMM and fused points (local frame) for a plot.
struct DrivePlot {
  std::vector<maps::Point2> truth, gps, hmm, fused;
  std::vector<std::uint8_t> in_outage;
};
StudyResult run_localization_study(const maps::RoadGraph& graph, const maps::EdgeSnapper& snapper,
                                   const std::map<std::string, std::vector<TruthSample>>& drives, const StudyConfig& config,
                                   const std::string& plot_id = "", DrivePlot* plot = nullptr);

// The edge a vehicle truly drives at `p` (local frame) with `heading_deg`: the nearest road point
// within radius_m whose direction agrees with the heading within 60°; invalid if none.
EdgeId true_edge(const maps::RoadGraph& graph, const maps::EdgeSnapper& snapper, maps::Point2 p, double heading_deg,
                 double radius_m);

// The OSM way of a SUMO lane id, as netconvert names edges after ways ("[-]<way>[#<part>]_<lane>");
// nothing for a lane inside a junction (":…") or an edge netconvert made up.
std::optional<std::int64_t> sumo_lane_osm_way(const std::string& lane);

// What a sample's vehicle truly drives: one edge, or, inside a SUMO junction, the edges before and
// after it and the OSM edges between them (the vehicle is somewhere on that way through).
struct TrueEdges {
  EdgeId edge;
  EdgeId alt;
  std::vector<EdgeId> through;  // inside a junction: the shortest way from `edge`'s head to `alt`'s tail
  bool from_lane = false;       // the lane's way chose `edge`
  EdgeId nearest;               // what true_edge() alone would say, for comparison
  [[nodiscard]] bool valid() const { return edge.valid(); }
  [[nodiscard]] bool contains(EdgeId e) const {
    return e.valid() && (e == edge || e == alt || std::find(through.begin(), through.end(), e) != through.end());
  }
};

// The true edges of a drive. A sample on a lane of OSM way W: the nearest edge of W whose
// direction agrees with the heading within 90°, so a parallel road or a lane offset cannot fool
// it, if it lies within 4 m more than true_edge()'s road (else SUMO's edge spans ways, and that
// road stands); none if the graph has no edge of W (the vehicle is off our roads); inside a
// junction: the edges before and after it and, where SUMO joined several OSM nodes into one
// junction, the short OSM edges between them; otherwise true_edge().
std::vector<TrueEdges> true_edges(const maps::RoadGraph& graph, const maps::EdgeSnapper& snapper,
                                  const std::vector<TruthSample>& samples, double radius_m);

// An SVG of one drive: truth, raw GPS dots, HMM-matched and fused tracks, the outage highlighted,
// over the roads near it.
std::string drive_plot_svg(const maps::RoadGraph& graph, const DrivePlot& plot, const std::string& title);

}  // namespace corridor::localizer
