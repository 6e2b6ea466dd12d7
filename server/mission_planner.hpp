// One mission's D* Lite, on the turn graph with the mission's own cost model, or on the shared
// contraction hierarchy with its model's metric (server/shared_hierarchy.hpp). The dispatch
// service drives both the same way: tell it what changed, move its start, repair, read the route.
#pragma once

#include <memory>
#include <span>
#include <vector>

#include "planner/dstar_lite.hpp"
#include "server/shared_hierarchy.hpp"

namespace corridor::server {

class MissionPlanner {
 public:
  MissionPlanner() = default;
  // On the turn graph: `cost` is the mission's own, kept here.
  MissionPlanner(std::unique_ptr<planner::TravelCost> cost, std::vector<planner::EdgePoint> starts,
                 std::vector<planner::EdgePoint> goals);
  // On the hierarchy: the model is shared with the other missions of its profile.
  MissionPlanner(std::shared_ptr<const HierarchyModel> model, std::vector<planner::EdgePoint> starts,
                 std::vector<planner::EdgePoint> goals);

  [[nodiscard]] bool active() const { return flat_ || cch_; }
  // Drops the search state (and this mission's hold on its model).
  void reset();
  [[nodiscard]] const HierarchyModel* model() const { return model_.get(); }

  // The overlay changed these edges and, on the hierarchy, the model's customization moved these
  // arcs (batches for other models must not be passed). Each change must be told exactly once.
  void changed(std::span<const EdgeId> edges, std::span<const ArcBatch> arcs);
  void move_start(std::vector<planner::EdgePoint> starts);
  void replan();
  [[nodiscard]] planner::Route route() const;
  // The mission's own search state (the shared model is not counted).
  [[nodiscard]] std::size_t memory_bytes() const;

 private:
  std::unique_ptr<planner::TravelCost> cost_;
  std::unique_ptr<planner::DStarLite> flat_;
  std::shared_ptr<const HierarchyModel> model_;
  std::unique_ptr<planner::CchDStarLite> cch_;
};

}  // namespace corridor::server
