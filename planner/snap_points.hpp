// Route endpoints from a snapped coordinate: the points on both directions of a two-way street, or,
// for a coordinate at an intersection, every edge that leaves (start) or arrives at (goal) it.
#pragma once

#include <vector>

#include "maps/edge_snapper.hpp"
#include "planner/travel_cost.hpp"

namespace corridor::planner {

enum class PointRole { start, goal };

// A snap this close to an edge's end is at the intersection there. A click on a junction, or an
// OSM test point placed on a node, lands within this of the node; a vehicle that close to the stop
// line can still take every exit.
inline constexpr double kAtNodeM = 1.0;

// Mid-edge: both directions of the snapped road (one on a one-way road). At a node: a start may
// leave by every out-edge (offset 0) and a goal may be reached by every in-edge (at its end), so a
// route neither detours to reach the one edge a nearest-segment snap happened to pick, nor lists an
// edge it does not drive. Without that, the snap kept one edge of the node, and a route from a
// junction went round the block (500 m instead of 100 m in a grid) or turned back at the far node.
std::vector<EdgePoint> points_from_snap(const maps::RoadGraph& graph, const maps::SnapResult& snap, PointRole role);

// The node a snapped coordinate lies on (within kAtNodeM of an end of its edge), or invalid.
NodeId node_at_snap(const maps::RoadGraph& graph, const maps::SnapResult& snap);

}  // namespace corridor::planner
