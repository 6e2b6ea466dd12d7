// A hand-made graph with known travel times, for tests that check exact values.
#pragma once

#include "maps/graph_builder.hpp"

namespace corridor::planner::testing {

// A(0,0) -- B(100,0) -- C(200,0), all two-way at 10 m/s, plus a detour A -- D(100,100) -- C at
// 20 m/s. Nodes: A=osm 1, B=2, C=3, D=4.
inline maps::RoadGraph diamond() {
  maps::GraphBuildInput in;
  in.origin = {47.0, 9.5};
  in.node_pos = {{0, 0}, {100, 0}, {200, 0}, {100, 100}};
  in.node_osm = {OsmNodeId{1}, OsmNodeId{2}, OsmNodeId{3}, OsmNodeId{4}};
  in.node_signalized = {0, 1, 0, 0};
  auto segment = [&](std::uint32_t a, std::uint32_t b, float speed, std::int64_t way) {
    maps::RoadSegment s;
    s.from = a;
    s.to = b;
    s.first_point = static_cast<std::uint32_t>(in.points.size());
    in.points.push_back(in.node_pos[a]);
    in.points.push_back(in.node_pos[b]);
    s.last_point = s.first_point + 1;
    s.forward_speed_mps = s.backward_speed_mps = speed;
    s.way = OsmWayId{way};
    in.segments.push_back(s);
  };
  segment(0, 1, 10.0f, 1);
  segment(1, 2, 10.0f, 2);
  segment(0, 3, 20.0f, 3);
  segment(3, 2, 20.0f, 4);
  return maps::build_road_graph(in);
}

inline EdgeId edge_from_to(const maps::RoadGraph& g, std::int64_t from_osm, std::int64_t to_osm) {
  for (EdgeId e : g.edges()) {
    if (g.osm_node(g.tail(e)).v == from_osm && g.osm_node(g.head(e)).v == to_osm) return e;
  }
  return kInvalidEdge;
}

}  // namespace corridor::planner::testing
