#include "planner/route_geojson.hpp"

#include <cmath>

namespace corridor::planner {
namespace {
// 1e-7 degrees is about 1 cm: the precision of OSM itself.
double round7(double v) { return std::round(v * 1e7) / 1e7; }
}  // namespace

nlohmann::json route_to_geojson(const maps::RoadGraph& graph, const Route& route, const char* algorithm) {
  nlohmann::json coordinates = nlohmann::json::array();
  for (const maps::Point2& p : route_polyline(graph, route)) {
    const maps::LatLon ll = graph.projection().to_lat_lon(p);
    coordinates.push_back({round7(ll.lon_deg), round7(ll.lat_deg)});
  }
  nlohmann::json edges = nlohmann::json::array();
  for (EdgeId e : route.edges) edges.push_back(e.v);
  nlohmann::json nodes = nlohmann::json::array(), osm_nodes = nlohmann::json::array(),
                 arrival = nlohmann::json::array(), signals = nlohmann::json::array();
  for (std::size_t i = 0; i < route.nodes.size(); ++i) {
    nodes.push_back(route.nodes[i].v);
    osm_nodes.push_back(graph.osm_node(route.nodes[i]).v);
    arrival.push_back(std::round(route.arrival_s[i] * 1000.0) / 1000.0);
    if (graph.signalized(route.nodes[i])) signals.push_back(route.nodes[i].v);
  }
  return {
      {"type", "Feature"},
      {"geometry", {{"type", "LineString"}, {"coordinates", std::move(coordinates)}}},
      {"properties",
       {{"travel_time_s", route.travel_time_s},
        {"length_m", route.length_m},
        {"algorithm", algorithm},
        {"nodes", std::move(nodes)},
        {"edges", std::move(edges)},
        {"osm_nodes", std::move(osm_nodes)},
        {"arrival_s", std::move(arrival)},
        {"signals", std::move(signals)}}},
  };
}

}  // namespace corridor::planner
