#include "server/mission_planner.hpp"

namespace corridor::server {

MissionPlanner::MissionPlanner(std::unique_ptr<planner::TravelCost> cost, std::vector<planner::EdgePoint> starts,
                               std::vector<planner::EdgePoint> goals)
    : cost_(std::move(cost)), flat_(std::make_unique<planner::DStarLite>(*cost_, std::move(starts), std::move(goals))) {}

MissionPlanner::MissionPlanner(std::shared_ptr<const HierarchyModel> model, std::vector<planner::EdgePoint> starts,
                               std::vector<planner::EdgePoint> goals)
    : model_(std::move(model)),
      cch_(std::make_unique<planner::CchDStarLite>(model_->metric, std::move(starts), std::move(goals))) {}

void MissionPlanner::reset() {
  // The planners point into the cost and the model: they go first.
  flat_.reset();
  cch_.reset();
  cost_.reset();
  model_.reset();
}

void MissionPlanner::changed(std::span<const EdgeId> edges, std::span<const ArcBatch> arcs) {
  if (flat_) {
    if (!edges.empty()) flat_->edges_changed(edges);
    return;
  }
  // The goal's own turns read the overlay directly; everything else comes through the metric.
  if (!edges.empty()) cch_->edges_changed(edges);
  for (const ArcBatch& batch : arcs) cch_->arcs_changed(*batch);
}

void MissionPlanner::move_start(std::vector<planner::EdgePoint> starts) {
  if (flat_) {
    flat_->move_start(std::move(starts));
  } else {
    cch_->move_start(std::move(starts));
  }
}

void MissionPlanner::replan() {
  if (flat_) {
    flat_->replan();
  } else {
    cch_->replan();
  }
}

planner::Route MissionPlanner::route() const { return flat_ ? flat_->route() : cch_->route(); }

std::size_t MissionPlanner::memory_bytes() const {
  if (flat_) return flat_->memory_bytes();
  return cch_ ? cch_->memory_bytes() : 0;
}

}  // namespace corridor::server
