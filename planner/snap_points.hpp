// Route endpoints from a snapped coordinate: the points on both directions of a two-way street, or,
// for a coordinate at an intersection, every edge that leaves (start) or arrives at (goal) it.
#pragma once

#include <optional>
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

// True when both snaps lie at the same node. The goal is then where the start already is: plan to
// the start's own points, which gives an empty route. The node's in-edges, the goal points of a
// junction, would send a start that leaves the node out and back, round a block or to the far
// dead end to turn (a 1 km loop from a dead end to itself).
bool at_same_node(const maps::RoadGraph& graph, const maps::SnapResult& a, const maps::SnapResult& b);

// A component of fewer nodes is small (OSRM's default, `--small-component-size`). A small largest
// component is taken for the main one only when no other is as large: on a clip of a few streets
// cut at its border, the network they mostly form; on two separate test streets of equal size,
// neither, and the nearest road wins.
inline constexpr std::size_t kSmallComponentNodes = 1000;

// The snap to plan from or to instead when no route joins the nearest roads: the nearest road of
// the graph's main component, when `nearest` lies off it, that component is not small, and one of
// its roads is within reach of p. So a click beside a car park that joins no public road reaches
// the street beside it rather than failing, while a route onto a one-way street that leaves the
// extract, which exists, is planned as clicked. nullopt: no such snap, keep the nearest.
std::optional<maps::SnapResult> main_component_snap(const maps::EdgeSnapper& snapper, const maps::RoadGraph& graph,
                                                    maps::LatLon p, const maps::SnapResult& nearest,
                                                    maps::SnapOptions options);

// Plans between the nearest roads, `plan(from, to)` returning whether it found a route. When it
// found none, an end with a main_component_snap moves there: one end at a time first (a start on
// an island must not move a destination that is reachable as clicked), then both. `from` and `to`
// are left at the snaps of the last plan.
template <class Plan>
bool plan_nearest_or_main(const maps::EdgeSnapper& snapper, const maps::RoadGraph& graph, maps::LatLon from_p,
                          maps::SnapResult& from, maps::LatLon to_p, maps::SnapResult& to, const maps::SnapOptions& options,
                          Plan&& plan) {
  if (plan(from, to)) return true;
  const auto from_main = main_component_snap(snapper, graph, from_p, from, options);
  const auto to_main = main_component_snap(snapper, graph, to_p, to, options);
  const maps::SnapResult from_nearest = from, to_nearest = to;
  if (from_main && plan(*from_main, to_nearest)) {
    from = *from_main;
    return true;
  }
  if (to_main && plan(from_nearest, *to_main)) {
    to = *to_main;
    return true;
  }
  if (!from_main || !to_main) return false;
  from = *from_main;
  to = *to_main;
  return plan(from, to);
}

}  // namespace corridor::planner
