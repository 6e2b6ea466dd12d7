// GeoJSON (RFC 7946, lon/lat) for routes: what `corridor route` prints and the API will return.
#pragma once

#include <nlohmann/json.hpp>

#include "planner/route.hpp"

namespace corridor::planner {

// A Feature whose geometry is the route's LineString and whose properties hold travel_time_s,
// length_m, algorithm, nodes (graph node ids crossed), edges, osm_nodes, arrival_s, signals,
// edge_coordinate_index (where each edge's piece starts in the coordinates), names (each edge's
// street) and steps (turn by turn, as OSRM's). With `congestion_factors` (one per edge), also
// congestion_factors, for colouring the route; a closed edge's factor is null.
nlohmann::json route_to_geojson(const maps::RoadGraph& graph, const Route& route, const char* algorithm,
                                const std::vector<double>* congestion_factors = nullptr);

// OSRM-style step objects: name, ref, distance_m, duration_s, maneuver {type, modifier, location}.
nlohmann::json steps_to_json(const maps::RoadGraph& graph, const Route& route);

}  // namespace corridor::planner
