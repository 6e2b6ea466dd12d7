// Random but seeded trips for the analytical experiments: start/goal pairs, signal delays, and
// unforeseen congestion placed on and near the planned route at times before the vehicle gets there.
#pragma once

#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "planner/experiments/trip_simulator.hpp"

namespace corridor::planner {

// SplitMix64: tiny, fast and, unlike std::uniform_real_distribution, the same sequence from every
// standard library, so that a seed gives the same CSV everywhere.
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : state_(seed) {}
  std::uint64_t next();
  double uniform();                          // [0, 1)
  double uniform(double lo, double hi);      // [lo, hi); lo when lo == hi
  std::uint32_t below(std::uint32_t n);      // [0, n)

 private:
  std::uint64_t state_;
};

// A seed for one named stream, so that each experiment's numbers do not depend on which other
// experiments ran before it.
std::uint64_t derive_seed(std::uint64_t seed, std::string_view stream);

struct DelayRange {
  double lo_s = 0.0;
  double hi_s = 0.0;  // uniform in [lo, hi]; fixed when equal
};

struct CongestionPlacement {
  std::uint32_t on_route = 2;    // edges of the planned route (never its first, already taken)
  std::uint32_t near_route = 2;  // edges off the route, within two intersections of it
};

// Congested links chosen for a trip, before their delays and times are drawn.
struct CongestionSites {
  std::vector<EdgeId> edges;
  std::vector<double> reach_s;  // when the planned vehicle reaches each edge's decision point
};

// Signal delays: drawn per node where has_signal is set (or the graph's signalized
// intersections); 0 elsewhere.
std::vector<double> draw_signal_delays(std::span<const std::uint8_t> has_signal, DelayRange range, Rng& rng);
std::vector<double> draw_signal_delays(const maps::RoadGraph& graph, DelayRange range, Rng& rng);

// 1 for every node that joins at least three roads: the "every intersection" of the paper's model,
// on maps where few signals are mapped.
std::vector<std::uint8_t> junction_mask(const maps::RoadGraph& graph);

// Picks the congested links for a trip from its static plan without preemption.
CongestionSites pick_congestion_sites(const maps::RoadGraph& graph, const Route& plan, CongestionPlacement placement,
                                      Rng& rng);

// One event per site: a delay from `queue`, at a time uniform in (0, reach] after departure. On the
// route, reach is when the planned vehicle gets to the edge, so that it could still avoid it if
// told in time; off the route, reach is the planned trip's end.
std::vector<CongestionEvent> draw_events(const CongestionSites& sites, DelayRange queue, Rng& rng);

// A random pair whose base route has at least `min_edges` edges and whose ends are at least
// `min_distance_m` apart in a straight line. Throws std::runtime_error if none is found.
std::pair<NodeId, NodeId> draw_pair(const maps::RoadGraph& graph, double min_distance_m, std::uint32_t min_edges,
                                    VehicleProfile vehicle, Rng& rng);

}  // namespace corridor::planner
