// Turns road segments between intersections into the CSR RoadGraph: directed edges, twins and
// geometry, every strongly connected component kept (the largest is the graph's main component).
#pragma once

#include <cstdint>
#include <vector>

#include "maps/road_graph.hpp"

namespace corridor::maps {

// One stretch of road between two graph nodes, in the local metric frame.
struct RoadSegment {
  std::uint32_t from = 0;  // index into GraphBuildInput nodes
  std::uint32_t to = 0;
  std::uint32_t first_point = 0;  // polyline = points[first_point .. last_point], from -> to
  std::uint32_t last_point = 0;
  bool forward = true;
  bool backward = true;
  float forward_speed_mps = 0.0f;
  float backward_speed_mps = 0.0f;
  OsmWayId way;
  RoadClass road_class = RoadClass::residential;
  std::uint32_t name = 0;  // ids into GraphBuildInput::strings (0: none)
  std::uint32_t ref = 0;
  float max_height_m = 0;  // 0: no limit
  float max_width_m = 0;
  float max_weight_t = 0;
  bool roundabout = false;
};

struct GraphBuildInput {
  LatLon origin;
  std::vector<Point2> node_pos;
  std::vector<OsmNodeId> node_osm;
  std::vector<std::uint8_t> node_signalized;
  // 1 where a barrier stands that the vehicle passes but stops at (a gate, a toll booth). Empty, or
  // one per node.
  std::vector<std::uint8_t> node_stop;
  std::vector<RoadSegment> segments;
  std::vector<Point2> points;
  StringTable strings;  // street names and refs of the segments
};

struct GraphBuildReport {
  std::size_t input_nodes = 0;
  std::size_t kept_nodes = 0;
  std::size_t dropped_nodes = 0;  // on no drivable road
  std::size_t kept_edges = 0;
  std::size_t components = 0;  // strongly connected components of the kept nodes
  std::size_t largest_component_nodes = 0;  // the main component
  std::size_t signalized_nodes = 0;
};

struct GraphBuildOptions {
  // Keep only the main component (a generated network for experiments, where every pair of nodes
  // must be joined); an imported map keeps every road.
  bool main_component_only = false;
};

// Throws MapLoadError when no drivable road remains.
RoadGraph build_road_graph(const GraphBuildInput& input, GraphBuildReport* report = nullptr,
                           const GraphBuildOptions& options = {});

}  // namespace corridor::maps
