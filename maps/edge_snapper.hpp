// Snaps a lat/lon to the nearest point on a drivable edge, through an R-tree over edge segments.
#pragma once

#include <memory>
#include <vector>

#include "maps/road_graph.hpp"

namespace corridor::maps {

struct SnapOptions {
  double max_distance_m = 200.0;  // farther than this from every road is an error
  bool main_component_only = false;  // only roads of the graph's main component (RoadGraph)
  // Only roads a trip may start or end on, not ferries: a click beside a ferry berth means the quay
  // road, as OSRM's car never starts or stops on a ferry. A vehicle's own position fix keeps them
  // (it may be riding one).
  bool skip_ferries = false;
};

struct SnapResult {
  EdgeId edge;          // the edge whose geometry is nearest
  double offset_m = 0;  // along `edge`, from its tail, in the edge's length units
  double distance_m = 0;  // from the query to the road
  Point2 point;           // the snapped point in the local frame
  EdgeId twin;            // the same road in the other direction, or invalid
  double twin_offset_m = 0;
};

class EdgeSnapper {
 public:
  explicit EdgeSnapper(const RoadGraph& graph);
  ~EdgeSnapper();
  EdgeSnapper(const EdgeSnapper&) = delete;
  EdgeSnapper& operator=(const EdgeSnapper&) = delete;

  // Throws SnapError for an invalid coordinate, one outside the map, or one too far from any road.
  [[nodiscard]] SnapResult snap(LatLon p, const SnapOptions& options = {}) const;
  [[nodiscard]] SnapResult snap_local(Point2 p, const SnapOptions& options = {}) const;

  // Every road within radius_m of p (local frame), nearest first, at most max_count roads; each
  // result is the nearest point of one road (twin filled in as by snap). Empty when none is near
  // or p is not finite. For map matching, which weighs several candidates rather than the nearest.
  [[nodiscard]] std::vector<SnapResult> candidates_local(Point2 p, double radius_m, std::size_t max_count) const;

 private:
  struct Index;
  const RoadGraph& graph_;
  std::unique_ptr<Index> index_;
};

}  // namespace corridor::maps
