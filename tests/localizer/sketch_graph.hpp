// Hand-drawn road graphs for the localizer's tests: nodes in the local frame, roads through them.
#pragma once

#include <vector>

#include "maps/graph_builder.hpp"

namespace corridor::localizer::testing {

// A graph from polylines in the local frame: each road is a list of node indices (two-way unless
// one-way), with straight geometry between them.
struct Sketch {
  std::vector<maps::Point2> nodes;
  struct Road {
    std::vector<std::uint32_t> through;
    bool oneway = false;
    std::int64_t way = 0;
    maps::RoadClass road_class = maps::RoadClass::residential;
  };
  std::vector<Road> roads;

  maps::RoadGraph build() const {
    maps::GraphBuildInput in;
    in.origin = {47.0, 9.5};
    in.node_pos = nodes;
    for (std::size_t i = 0; i < nodes.size(); ++i) {
      in.node_osm.push_back(OsmNodeId{static_cast<std::int64_t>(i + 1)});
      in.node_signalized.push_back(0);
    }
    for (const Road& r : roads) {
      for (std::size_t k = 1; k < r.through.size(); ++k) {
        maps::RoadSegment s;
        s.from = r.through[k - 1];
        s.to = r.through[k];
        s.first_point = static_cast<std::uint32_t>(in.points.size());
        in.points.push_back(nodes[s.from]);
        in.points.push_back(nodes[s.to]);
        s.last_point = s.first_point + 1;
        s.forward = true;
        s.backward = !r.oneway;
        s.forward_speed_mps = s.backward_speed_mps = 14.0f;
        s.way = OsmWayId{r.way};
        s.road_class = r.road_class;
        in.segments.push_back(s);
      }
    }
    return maps::build_road_graph(in);
  }
};

// One two-way road (way 1) from (0, 0) east to (length_m, 0).
inline maps::RoadGraph straight_road(double length_m) {
  Sketch s;
  s.nodes = {{0, 0}, {length_m, 0}};
  s.roads = {{{0, 1}, false, 1}};
  return s.build();
}

// The directed edge from the node at `from` to the node at `to` (within a metre), or invalid.
inline EdgeId edge_between(const maps::RoadGraph& g, maps::Point2 from, maps::Point2 to) {
  for (EdgeId e : g.edges()) {
    if (maps::distance_m(g.position(g.tail(e)), from) < 1.0 && maps::distance_m(g.position(g.head(e)), to) < 1.0) return e;
  }
  return EdgeId{};
}

}  // namespace corridor::localizer::testing
