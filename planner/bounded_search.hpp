// Bounded one-to-many shortest distances on the road graph, by length: Dijkstra from one node
// until every target is settled or the bound is passed. The map matcher's transition model asks it
// for the network distance between consecutive candidates. The arrays are kept between runs, so a
// run costs what it visits.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "maps/road_graph.hpp"
#include "planner/cost.hpp"

namespace corridor::planner {

class BoundedDistances {
 public:
  // Scratch arrays for a graph of this many nodes; any graph of that size may be searched with them.
  explicit BoundedDistances(std::size_t node_count);

  // Distances from `source` along the graph's edges, up to max_length_m; stops early once every
  // node in `targets` is settled. Returns the number of nodes settled.
  std::size_t run(const maps::RoadGraph& graph, NodeId source, double max_length_m, std::span<const NodeId> targets = {});
  [[nodiscard]] std::size_t node_count() const { return dist_.size(); }
  // After run(): the edges of a shortest path from the source to v (empty for the source itself or
  // a node the run did not settle).
  [[nodiscard]] std::vector<EdgeId> path_to(const maps::RoadGraph& graph, NodeId v) const;

  // After run(): the shortest length to v if the run settled it (every target within the bound
  // is), else kInfCost.
  [[nodiscard]] double length_m(NodeId v) const {
    return settled_[v.index()] == round_ ? dist_[v.index()] : kInfCost;
  }

 private:
  std::vector<double> dist_;
  std::vector<std::uint32_t> stamp_;    // dist_ is valid where stamp_ == round_
  std::vector<std::uint32_t> settled_;  // settled in the round stored here
  std::vector<EdgeId> parent_edge_;     // the edge a node was reached by, valid where stamped
  std::vector<std::pair<double, std::uint32_t>> heap_;
  std::uint32_t round_ = 0;
};

}  // namespace corridor::planner
