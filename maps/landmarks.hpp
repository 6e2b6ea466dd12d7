// ALT landmarks (Goldberg & Harrelson 2005): free-flow travel times to and from a few landmark
// nodes, from which the triangle inequality gives a lower bound on the travel time between any two
// nodes. Computed once per graph (at import, then kept in the graph cache) and shared by A* and
// D* Lite, so both baselines search with the same heuristic.
//
// Times are whole ticks of kLandmarkTickS on edge weights rounded down to a tick. Integer sums are
// exact, so the bound is exactly consistent: h(u) - h(v) is at most the rounded-down free-flow time
// of the arc u -> v, which is at most any cost the planner charges for it (congestion, queues and
// signals only add). A floating-point table would be consistent only up to rounding, and D* Lite's
// repairs are checked against Dijkstra to 1e-9.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "maps/ids.hpp"

namespace corridor::maps {

inline constexpr double kLandmarkTickS = 1.0 / 1024.0;
// Unreachable. Kept finite (and so summable): with it every triangle inequality the bound relies on
// still holds in integer arithmetic (see landmarks.cpp).
inline constexpr std::uint32_t kLandmarkUnreachable = 0xFFFFFFFFu;
inline constexpr std::size_t kDefaultLandmarkCount = 16;

struct RoadGraphData;

// The tables, node-major so that one node's K values share a cache line or two:
// from_ticks[v * K + i] = time from landmark i to v, to_ticks[v * K + i] = time from v to landmark i.
struct LandmarkTables {
  std::vector<NodeId> nodes;
  std::vector<std::uint32_t> from_ticks;
  std::vector<std::uint32_t> to_ticks;
};

// The lower-bound weight of an edge in ticks: length / legal speed, rounded down.
std::uint32_t free_flow_ticks(double length_m, double speed_mps);

// Chooses up to `count` landmarks by farthest selection (each new landmark is the node whose
// round-trip time to the nearest chosen one is largest, so they spread to the map's rim, where they
// bound best) and fills both tables. Needs the forward and reverse CSR of `data`. Only nodes with
// `candidate[v] != 0` are chosen (all when empty): RoadGraph passes its main component, since a
// node no landmark reaches would otherwise win every round, and a map with many cut-off roads would
// spend all its landmarks on them, where they bound nothing.
LandmarkTables compute_landmarks(const RoadGraphData& data, std::size_t count = kDefaultLandmarkCount,
                                 std::span<const std::uint8_t> candidate = {});

// The landmark lower bound in ticks on the travel time from a to b, given their table rows:
// max over landmarks of d(L,b) - d(L,a) and d(a,L) - d(b,L), and never below 0.
inline std::int64_t landmark_bound_ticks(std::span<const std::uint32_t> from_a, std::span<const std::uint32_t> to_a,
                                         std::span<const std::uint32_t> from_b, std::span<const std::uint32_t> to_b) {
  std::int64_t best = 0;
  for (std::size_t i = 0; i < from_a.size(); ++i) {
    const std::int64_t forward = std::int64_t{from_b[i]} - std::int64_t{from_a[i]};
    const std::int64_t backward = std::int64_t{to_a[i]} - std::int64_t{to_b[i]};
    best = std::max(best, std::max(forward, backward));
  }
  return best;
}

}  // namespace corridor::maps
