// Live traffic conditions over an immutable RoadGraph: per-edge congestion factor and queue delay,
// closures, and per-node crossing delay (for example the expected signal delay). Shared by all
// planners of a server; planners are told which ids changed.
#pragma once

#include <stdexcept>
#include <vector>

#include "maps/road_graph.hpp"

namespace corridor::planner {

class CostUpdateError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

struct EdgeCondition {
  double congestion_factor = 1.0;  // multiplies free-flow running time; kInfCost closes the edge
  double queue_delay_s = 0.0;      // waiting at the downstream stop line
  friend bool operator==(const EdgeCondition&, const EdgeCondition&) = default;
};

class CostOverlay {
 public:
  explicit CostOverlay(const maps::RoadGraph& graph);

  // Throws CostUpdateError for an unknown id or a value that is negative, zero (factor) or NaN.
  void set_edge(EdgeId e, EdgeCondition condition);
  void close_edge(EdgeId e);
  void set_node_delay(NodeId v, double delay_s);
  // Sets the same crossing delay on every signalized intersection.
  void set_signal_delay(const maps::RoadGraph& graph, double delay_s);
  void reset_edge(EdgeId e) { set_edge(e, EdgeCondition{}); }

  [[nodiscard]] const EdgeCondition& edge(EdgeId e) const { return edges_[e.index()]; }
  [[nodiscard]] double node_delay_s(NodeId v) const { return node_delay_s_[v.index()]; }
  [[nodiscard]] std::size_t edge_count() const { return edges_.size(); }
  [[nodiscard]] std::size_t node_count() const { return node_delay_s_.size(); }

 private:
  std::vector<EdgeCondition> edges_;
  std::vector<double> node_delay_s_;
};

}  // namespace corridor::planner
