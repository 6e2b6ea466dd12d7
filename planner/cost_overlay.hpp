// Live traffic conditions over an immutable RoadGraph: per-edge congestion factor and queue delay,
// closures, per-node crossing delay, and per-movement delay (the expected signal wait of one turn,
// from the green share of its movement). Shared by all planners of a server; planners are told
// which ids changed (a movement's delay changes through its node).
#pragma once

#include <cstdint>
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

  // The delay of the movement from `in` onto `out` at the node where they meet, on top of that
  // node's delay. Throws CostUpdateError for an unknown id, edges that do not meet (head(in) !=
  // tail(out)), or a value that is negative or not finite.
  void set_turn_delay(EdgeId in, EdgeId out, double delay_s);
  // 0 where none was set. Cheap: one load where the node has none, three where it has.
  // Precondition: head(in) == tail(out), as for every arc of the turn graph (not checked here).
  [[nodiscard]] double turn_delay_s(EdgeId in, EdgeId out) const {
    if (turn_row_.empty()) return 0.0;
    const std::uint32_t row = turn_row_[in.index()];
    if (row == 0) return 0.0;
    return turn_delay_s_[row - 1 + (out.v - first_out_at_head_[in.index()])];
  }
  [[nodiscard]] bool has_turn_delays() const { return !turn_row_.empty(); }
  [[nodiscard]] std::size_t edge_count() const { return edges_.size(); }
  [[nodiscard]] std::size_t node_count() const { return node_delay_s_.size(); }

 private:
  const maps::RoadGraph* graph_;
  std::vector<EdgeCondition> edges_;
  std::vector<double> node_delay_s_;
  // Per in-edge: 1 + where its row of delays (one per out-edge of its head, in CSR order) starts in
  // turn_delay_s_, or 0 for none; and the first out-edge id at its head. Allocated on first use.
  std::vector<std::uint32_t> turn_row_;
  std::vector<std::uint32_t> first_out_at_head_;
  std::vector<double> turn_delay_s_;
};

}  // namespace corridor::planner
