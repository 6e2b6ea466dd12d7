// The contraction hierarchy that the server's mission planners share (planner/cch_*.hpp): one
// topology for the map, and one metric for each cost model in use (a vehicle profile at a top
// speed), built when its first mission comes and dropped with its last. A congestion batch is
// customized once per metric and its moved arcs are handed to that metric's missions as one
// shared, immutable batch: the customization is paid once per batch, not once per mission.
//
// Threads: a metric is read by the missions' repairs under the overlay's shared lock and changed
// by edges_changed under its exclusive lock, so the caller's overlay lock is what guards it.
#pragma once

#include <map>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "planner/cch_metric.hpp"
#include "planner/cch_topology.hpp"
#include "planner/cost_overlay.hpp"
#include "planner/travel_cost.hpp"
#include "planner/vehicle_profile.hpp"

namespace corridor::server {

// The arcs one customization moved; the planners of that metric read it, nobody writes it.
using ArcBatch = std::shared_ptr<const std::vector<std::uint32_t>>;

// One cost model and its metric. The cost outlives the metric that points to it.
struct HierarchyModel {
  HierarchyModel(const planner::CchTopology& topology, const maps::RoadGraph& graph, const planner::CostOverlay& overlay,
                 planner::VehicleProfile profile)
      : cost(graph, overlay, std::move(profile)), metric(topology, cost) {}
  planner::TravelCost cost;
  planner::CchMetric metric;
};

class SharedHierarchy {
 public:
  // Builds the topology (a nested-dissection order and its contraction; 1.2 s on a metro area).
  // At most `max_models` metrics are kept at once.
  SharedHierarchy(const maps::RoadGraph& graph, const planner::CostOverlay& overlay, std::size_t max_models);

  [[nodiscard]] const planner::CchTopology& topology() const { return topology_; }
  // Arcs per vertex: how dense the contraction came out. Road networks with small separators
  // (rivers, ring roads, bridges) stay below 10; a city-wide grid has none and reaches 30.
  [[nodiscard]] double density() const;

  // The model for this profile: the one in use, or a new one (a full customization); null when
  // `max_models` other models are in use. Call with the overlay at least share-locked. Throws what
  // TravelCost throws for a bad profile.
  std::shared_ptr<const HierarchyModel> acquire(const planner::VehicleProfile& profile);

  // The overlay changed these edges' conditions; call under its exclusive lock. Customizes every
  // model in use and returns each one's moved arcs (models where none moved are left out).
  std::vector<std::pair<std::shared_ptr<const HierarchyModel>, ArcBatch>> edges_changed(std::span<const EdgeId> edges);

  // Models in use now, and the bytes of the topology and of their metrics (the latter with the
  // overlay at least share-locked, or with nothing else running: it reads the metrics' buffers).
  [[nodiscard]] std::size_t models_in_use() const;
  [[nodiscard]] std::size_t memory_bytes() const;

 private:
  const maps::RoadGraph& graph_;
  const planner::CostOverlay& overlay_;
  planner::CchTopology topology_;
  std::size_t max_models_;
  // Guards models_: acquire runs under the overlay's shared lock, so two may run at once.
  mutable std::mutex mutex_;
  // By the profile's JSON (every field that prices a turn or an edge).
  std::map<std::string, std::weak_ptr<HierarchyModel>> models_;
};

}  // namespace corridor::server
