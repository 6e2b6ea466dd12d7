#include "planner/route_geojson.hpp"

#include <cmath>

#include "planner/route_steps.hpp"

namespace corridor::planner {
namespace {
// 1e-7 degrees is about 1 cm: the precision of OSM itself.
double round7(double v) { return std::round(v * 1e7) / 1e7; }
}  // namespace

nlohmann::json steps_to_json(const maps::RoadGraph& graph, const Route& route) {
  nlohmann::json out = nlohmann::json::array();
  auto round1 = [](double v) { return std::round(v * 10.0) / 10.0; };
  for (const RouteStep& s : route_steps(graph, route)) {
    const maps::LatLon at = graph.projection().to_lat_lon(s.location);
    nlohmann::json maneuver{{"type", to_string(s.maneuver)},
                            {"location", {round7(at.lon_deg), round7(at.lat_deg)}}};
    maneuver["modifier"] = s.modifier == TurnModifier::none ? nlohmann::json(nullptr) : nlohmann::json(to_string(s.modifier));
    if (s.exit > 0) maneuver["exit"] = s.exit;
    out.push_back({{"name", s.name},
                   {"ref", s.ref},
                   {"distance_m", round1(s.distance_m)},
                   {"duration_s", round1(s.duration_s)},
                   {"mode", s.ferry ? "ferry" : "driving"},
                   {"maneuver", std::move(maneuver)}});
  }
  return out;
}

nlohmann::json route_to_geojson(const maps::RoadGraph& graph, const Route& route, const char* algorithm,
                                const std::vector<double>* congestion_factors) {
  nlohmann::json coordinates = nlohmann::json::array();
  std::vector<std::uint32_t> edge_first;
  for (const maps::Point2& p : route_polyline(graph, route, &edge_first)) {
    const maps::LatLon ll = graph.projection().to_lat_lon(p);
    coordinates.push_back({round7(ll.lon_deg), round7(ll.lat_deg)});
  }
  nlohmann::json edges = nlohmann::json::array();
  nlohmann::json names = nlohmann::json::array();
  for (EdgeId e : route.edges) {
    edges.push_back(e.v);
    names.push_back(graph.name(e));
  }
  nlohmann::json nodes = nlohmann::json::array(), osm_nodes = nlohmann::json::array(),
                 arrival = nlohmann::json::array(), signals = nlohmann::json::array();
  for (std::size_t i = 0; i < route.nodes.size(); ++i) {
    nodes.push_back(route.nodes[i].v);
    osm_nodes.push_back(graph.osm_node(route.nodes[i]).v);
    arrival.push_back(std::round(route.arrival_s[i] * 1000.0) / 1000.0);
    if (graph.signalized(route.nodes[i])) signals.push_back(route.nodes[i].v);
  }
  nlohmann::json feature{
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
        {"signals", std::move(signals)},
        {"edge_coordinate_index", std::move(edge_first)},
        {"names", std::move(names)},
        {"steps", steps_to_json(graph, route)}}},
  };
  if (congestion_factors != nullptr && congestion_factors->size() == route.edges.size()) {
    nlohmann::json factors = nlohmann::json::array();
    for (double f : *congestion_factors) {
      factors.push_back(std::isfinite(f) && f < 1e6 ? nlohmann::json(std::round(f * 100.0) / 100.0) : nlohmann::json(nullptr));
    }
    feature["properties"]["congestion_factors"] = std::move(factors);
  }
  return feature;
}

}  // namespace corridor::planner
