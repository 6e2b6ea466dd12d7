// The grid, the mission request and the status probe the DispatchService tests share: one 10×10
// two-way grid with signals at half its nodes, and a mission from one corner to the other.
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "maps/synthetic_grid.hpp"
#include "server/dispatch_service.hpp"

namespace corridor::server::testing {

inline maps::RoadGraph test_grid() {
  maps::GridSpec spec;
  spec.rows = 10;
  spec.cols = 10;
  spec.seed = 21;
  spec.oneway_fraction = 0.0;
  spec.removal_fraction = 0.0;
  spec.signal_fraction = 0.5;
  return maps::make_perturbed_grid(spec);
}

inline const maps::RoadGraph& grid() {
  static const maps::RoadGraph g = test_grid();
  return g;
}

inline maps::LatLon node_ll(NodeId n) { return grid().projection().to_lat_lon(grid().position(n)); }
inline maps::LatLon corner(bool far) { return node_ll(NodeId{far ? static_cast<std::uint32_t>(grid().node_count() - 1) : 0u}); }

inline MissionRequest request(const std::string& vehicle) {
  MissionRequest r;
  r.vehicle_id = vehicle;
  r.origin = corner(false);
  r.destination = corner(true);
  r.priority = 2;
  return r;
}

inline int code_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const ApiError& e) {
    return e.status();
  }
  return 0;
}

}  // namespace corridor::server::testing
