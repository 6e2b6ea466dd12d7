#include "planner/snap_points.hpp"

namespace corridor::planner {

std::vector<EdgePoint> points_from_snap(const maps::RoadGraph& graph, const maps::SnapResult& snap, PointRole role) {
  std::vector<EdgePoint> both{{snap.edge, snap.offset_m}};
  if (!snap.twin.valid()) return both;
  both.push_back({snap.twin, snap.twin_offset_m});
  constexpr double kAtNodeM = 0.01;
  for (std::size_t i = 0; i < 2; ++i) {
    const double off = both[i].offset_m;
    const double len = graph.length_m(both[i].edge);
    const bool empty_piece = role == PointRole::goal ? off <= kAtNodeM : off >= len - kAtNodeM;
    if (empty_piece) return {both[1 - i]};
  }
  return both;
}

}  // namespace corridor::planner
