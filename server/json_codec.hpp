// JSON in and out of the API: strict parsing of request bodies into the service's structs (every
// field checked for presence, type and range, with the field named in the error) and rendering of
// missions, schedules and events.
#pragma once

#include <nlohmann/json.hpp>

#include "maps/road_graph.hpp"
#include "server/dispatch_types.hpp"

namespace corridor::server {

// Throws ApiError(400) for malformed JSON, naming what is wrong.
nlohmann::json parse_body(const std::string& body);

MissionRequest mission_request_from_json(const nlohmann::json& j);
PositionReport position_from_json(const nlohmann::json& j, const std::string& vehicle_id);
std::vector<CongestionUpdate> congestion_from_json(const nlohmann::json& j);

// What a signal's detectors measured on one approach over the last period: counts (loops at the
// approach's entry and stop line), occupancy or a measured/free speed ratio (the congestion
// classifier's input where no queue estimate exists), and the standing queue's length (a lane-area
// detector's jam length, or a queue detector's): the vicinity rules' input. Each part is optional,
// at least one is given, and counts come in pairs.
struct CountsReport {
  maps::Compass approach;
  std::optional<double> arrivals;
  std::optional<double> departures;
  std::optional<double> occupancy;
  std::optional<double> speed_ratio;
  std::optional<double> queue_m;
};
CountsReport counts_from_json(const nlohmann::json& j);

nlohmann::json mission_to_json(const maps::RoadGraph& graph, const MissionView& m);
nlohmann::json schedule_to_json(const maps::RoadGraph& graph, const std::vector<preemption::ScheduleEntry>& schedule);
nlohmann::json event_to_json(const DispatchEvent& e);
nlohmann::json vehicle_to_json(const VehicleView& v);
nlohmann::json revision_to_json(const RouteRevisionView& r);
nlohmann::json error_json(const std::string& code, const std::string& message);

}  // namespace corridor::server
