// GeoJSON (RFC 7946, lon/lat) for routes: what `corridor route` prints and the API will return.
#pragma once

#include <nlohmann/json.hpp>

#include "planner/route.hpp"

namespace corridor::planner {

// A Feature whose geometry is the route's LineString and whose properties hold travel_time_s,
// length_m, algorithm, nodes (graph node ids crossed), edges, osm_nodes, arrival_s and signals.
nlohmann::json route_to_geojson(const maps::RoadGraph& graph, const Route& route, const char* algorithm);

}  // namespace corridor::planner
