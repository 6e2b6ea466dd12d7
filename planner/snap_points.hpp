// Route endpoints from a snapped coordinate: the points on both directions of a two-way street,
// without zero-length pieces where the coordinate lies on a node.
#pragma once

#include <vector>

#include "maps/edge_snapper.hpp"
#include "planner/travel_cost.hpp"

namespace corridor::planner {

enum class PointRole { start, goal };

// Both directions of the snapped road. At a node the two are one place: a goal keeps the end of
// the edge arriving there and a start the beginning of the edge leaving it, so a route never lists
// an edge it does not drive.
std::vector<EdgePoint> points_from_snap(const maps::RoadGraph& graph, const maps::SnapResult& snap, PointRole role);

}  // namespace corridor::planner
