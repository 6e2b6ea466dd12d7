// One mission's state inside the dispatch service: its row, planner and route, each confined to
// the mission's own lock. Private to the service's implementation files.
#pragma once

#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "maps/errors.hpp"
#include "server/api_error.hpp"
#include "server/dispatch_service.hpp"

namespace corridor::server {

struct DispatchService::Mission {
  // Confines everything below but the pending changes: one request works on a mission at a time.
  mutable std::mutex mutex;
  MissionRow row;
  std::optional<maps::LatLon> last_position;
  maps::Point2 destination_local;
  MissionPlanner planner;
  // The planner's hierarchy model, set before the mission is shared and never changed: congestion
  // changes match their arc batches to missions by it without the mission's lock. An identity only;
  // the planner holds the model itself.
  const HierarchyModel* model = nullptr;
  planner::Route route;
  std::uint32_t revision = 0;
  std::vector<preemption::ScheduleEntry> final_schedule;  // kept when the engine forgets the mission
  double route_time_s = 0;  // when `route` was last computed
  // Route revisions, oldest first: what was stored (restored from the store after a restart, with
  // its geometry) and, for revisions made in this process, the route, rendered when asked for.
  struct Revision {
    RouteRevisionView view;
    std::optional<planner::Route> route;
  };
  std::vector<Revision> history;

  // Edges whose cost changed since the planner last heard, and the reason to give if the repaired
  // route differs. Appended under the overlay's exclusive lock, taken under its shared lock, so a
  // repair sees exactly the costs it was told of.
  std::mutex pending_mutex;
  std::vector<EdgeId> pending_edges;
  std::vector<ArcBatch> pending_arcs;  // the hierarchy's moved arcs, one batch per customization
  std::optional<std::string> pending_reason;
};

// A point that cannot be put on the map, as the API's 422 with its reason's code.
inline ApiError snap_error(const maps::SnapError& e, const char* what) {
  const char* code = e.reason() == maps::SnapError::Reason::invalid_coordinate ? "invalid_coordinate"
                     : e.reason() == maps::SnapError::Reason::outside_map  ? "outside_map"
                                                                            : "off_road";
  return unprocessable(code, std::string(what) + ": " + e.what());
}

}  // namespace corridor::server
