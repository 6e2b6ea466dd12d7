// Plain request and view structs of the dispatch service: what clients ask for and what they see.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "maps/geo.hpp"
#include "maps/ids.hpp"
#include "planner/route.hpp"
#include "preemption/engine.hpp"

namespace corridor::server {

class CommitTicket;  // server/commit_queue.hpp

using MissionId = std::uint64_t;

enum class MissionState { active, completed, cancelled };
const char* to_string(MissionState s);
std::optional<MissionState> mission_state_from(const std::string& s);

struct MissionRequest {
  std::string vehicle_id;
  maps::LatLon destination;
  std::optional<maps::LatLon> origin;  // else the vehicle's last known position
  int priority = 1;
  double vmax_kmh = 120.0;
  std::string profile = "ambulance";  // a built-in vehicle profile: ambulance or fire_engine
};

struct PositionReport {
  std::string vehicle_id;
  maps::LatLon position;
  std::optional<double> heading_deg;
  std::optional<double> speed_mps;
  std::optional<double> hdop;
  double timestamp_s = 0;
  std::string source = "gps";  // gps | vo
};

struct CongestionUpdate {
  std::optional<EdgeId> edge;
  std::optional<std::int64_t> osm_way_id;
  std::optional<double> speed_kmh;
  std::optional<double> travel_time_s;
  std::optional<double> factor;
  std::optional<double> expires_in_s;
};

struct MissionView {
  MissionId id = 0;
  std::string vehicle_id;
  MissionState state = MissionState::active;
  int priority = 1;
  double vmax_kmh = 120.0;
  std::string profile = "ambulance";
  maps::LatLon destination;
  std::optional<maps::LatLon> last_position;
  planner::Route route;
  std::uint32_t route_revision = 0;
  std::vector<preemption::ScheduleEntry> schedule;
  double created_s = 0;
  double updated_s = 0;
  double route_time_s = 0;  // when `route` was computed: its arrival times count from then
  std::vector<double> congestion_factors;  // per route edge, read with the route
};

// One stored revision of a mission's route: why it changed, and what it was.
struct RouteRevisionView {
  std::uint32_t revision = 0;
  std::string reason;
  double time_s = 0;
  double eta_s = 0;
  double length_m = 0;
  std::string geometry_json;  // a GeoJSON LineString
};

// A vehicle's latest accepted report.
struct VehicleView {
  std::string vehicle_id;
  maps::LatLon position;
  std::optional<double> heading_deg;
  std::optional<double> speed_mps;
  double timestamp_s = 0;
  std::string source = "gps";
  std::optional<MissionId> mission;
};

// What the tracker made of a position report: followed, or stored only (stale, duplicate, outlier,
// low_accuracy), and where the map matcher put it.
struct PositionMatch {
  std::string disposition = "followed";
  std::optional<EdgeId> edge;  // matched edge, when followed and matched
  double offset_m = 0;
  double confidence = 0;  // the matcher's probability share for the chosen road point, 0..1
};

struct PositionResult {
  std::optional<MissionId> mission;  // the vehicle's active mission, if any
  PositionMatch match;
  double snap_distance_m = 0;
  bool route_changed = false;
  bool completed = false;
  double eta_s = 0;
  std::shared_ptr<CommitTicket> durable;  // when the report and its consequences are stored
};

struct CongestionResult {
  std::size_t edges_changed = 0;
  std::size_t missions_replanned = 0;
  std::size_t routes_changed = 0;
  // Of missions_replanned, those a position report had already repaired with this batch's changes
  // by the time the batch reached them; the samples below leave them out.
  std::size_t missions_repaired_by_reports = 0;
  // From the call's start to the last mission's repaired route: what a dispatcher waits, at most,
  // to see the effect of a congestion report (before its writes are durable).
  double replan_latency_s = 0;
  // The longest single mission's D* Lite repair in this batch, from before its lock was taken (0
  // when position reports had repaired every mission first).
  double slowest_replan_s = 0;
  // Each mission's D* Lite repair time, in no particular order: the per-replan latency (the
  // batch's own repairs, not missions_repaired_by_reports).
  std::vector<double> mission_replan_s;
  // The same repairs in the repairing thread's own CPU time: the work, without the time the
  // thread waited for a core (on a loaded machine the two differ by the scheduler's slices).
  std::vector<double> mission_replan_cpu_s;
  // Customizing the shared hierarchy's metrics to the batch, once for all missions (0 on the turn
  // graph); paid under the overlay's exclusive lock, before the repairs.
  double customization_s = 0;
};

// What the service tells listeners (the WebSocket stream): kind and mission, with a JSON payload
// built by the codec.
struct DispatchEvent {
  std::string kind;  // mission_created, mission_completed, mission_cancelled, route_changed, position,
                     // preemption_<kind>, congestion_applied, signal_state, signal_call, signal_field
  MissionId mission = 0;
  std::string reason;
  double time_s = 0;
  std::uint64_t seq = 0;  // set by the service: increasing, so a client can order and deduplicate
  // What the kind carries (left empty by the others): the vehicle of a mission or position; the
  // position itself; a route's revision and remaining travel time; the signal of a preemption or
  // signal_state event and that signal's new state; the edges a congestion report changed.
  std::string vehicle_id;
  std::optional<maps::LatLon> position;
  std::optional<double> heading_deg;
  std::optional<double> speed_mps;
  std::optional<double> eta_s;
  std::string source;
  std::optional<std::uint32_t> revision;
  std::optional<NodeId> signal;
  std::string state;
  std::optional<std::size_t> edges_changed;
  // A signal_field event's field controller: its link, its own preempt state, whether Corridor calls.
  std::string link;
  std::string preempt_state;
  std::optional<bool> call_on;
};

}  // namespace corridor::server
