#include "server/shared_hierarchy.hpp"

namespace corridor::server {

SharedHierarchy::SharedHierarchy(const maps::RoadGraph& graph, const planner::CostOverlay& overlay, std::size_t max_models)
    : graph_(graph), overlay_(overlay), topology_(graph.turns()), max_models_(max_models) {}

double SharedHierarchy::density() const {
  return topology_.vertex_count() == 0 ? 0.0
                                       : static_cast<double>(topology_.arc_count()) / static_cast<double>(topology_.vertex_count());
}

std::shared_ptr<const HierarchyModel> SharedHierarchy::acquire(const planner::VehicleProfile& profile) {
  const std::string key = planner::profile_to_json(profile);
  std::lock_guard lock(mutex_);
  // Models whose last mission ended are gone; forget them here, where the map is locked anyway.
  std::erase_if(models_, [](const auto& kv) { return kv.second.expired(); });
  if (auto it = models_.find(key); it != models_.end()) {
    if (auto model = it->second.lock()) return model;
  }
  if (models_.size() >= max_models_) return nullptr;
  auto model = std::make_shared<HierarchyModel>(topology_, graph_, overlay_, profile);
  models_[key] = model;
  return model;
}

std::vector<std::pair<std::shared_ptr<const HierarchyModel>, ArcBatch>> SharedHierarchy::edges_changed(std::span<const EdgeId> edges) {
  std::vector<std::shared_ptr<HierarchyModel>> live;
  {
    std::lock_guard lock(mutex_);
    for (const auto& [key, weak] : models_) {
      if (auto model = weak.lock()) live.push_back(std::move(model));
    }
  }
  std::vector<std::pair<std::shared_ptr<const HierarchyModel>, ArcBatch>> out;
  for (const auto& model : live) {
    auto moved = std::make_shared<std::vector<std::uint32_t>>();
    model->metric.edges_changed(edges, *moved);
    if (!moved->empty()) out.emplace_back(model, std::move(moved));
  }
  return out;
}

std::size_t SharedHierarchy::models_in_use() const {
  std::lock_guard lock(mutex_);
  std::size_t n = 0;
  for (const auto& [key, weak] : models_) n += weak.expired() ? 0 : 1;
  return n;
}

std::size_t SharedHierarchy::memory_bytes() const {
  std::lock_guard lock(mutex_);
  std::size_t bytes = topology_.memory_bytes();
  for (const auto& [key, weak] : models_) {
    if (auto model = weak.lock()) bytes += model->metric.memory_bytes();
  }
  return bytes;
}

}  // namespace corridor::server
