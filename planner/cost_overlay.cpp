#include "planner/cost_overlay.hpp"

#include <cmath>
#include <string>

#include "planner/cost.hpp"

namespace corridor::planner {

CostOverlay::CostOverlay(const maps::RoadGraph& graph)
    : graph_(&graph), edges_(graph.edge_count()), node_delay_s_(graph.node_count(), 0.0) {}

void CostOverlay::set_edge(EdgeId e, EdgeCondition c) {
  if (!e.valid() || e.index() >= edges_.size()) {
    throw CostUpdateError("unknown edge id " + std::to_string(e.v) + " (the map has " + std::to_string(edges_.size()) +
                          " edges)");
  }
  if (!(c.congestion_factor > 0.0)) {
    throw CostUpdateError("congestion factor must be positive, got " + std::to_string(c.congestion_factor));
  }
  if (!(c.queue_delay_s >= 0.0) || !std::isfinite(c.queue_delay_s)) {
    throw CostUpdateError("queue delay must be a finite number of seconds >= 0, got " + std::to_string(c.queue_delay_s));
  }
  edges_[e.index()] = c;
}

void CostOverlay::close_edge(EdgeId e) { set_edge(e, {kInfCost, 0.0}); }

void CostOverlay::set_node_delay(NodeId v, double delay_s) {
  if (!v.valid() || v.index() >= node_delay_s_.size()) {
    throw CostUpdateError("unknown node id " + std::to_string(v.v));
  }
  if (!(delay_s >= 0.0) || !std::isfinite(delay_s)) {
    throw CostUpdateError("node delay must be a finite number of seconds >= 0, got " + std::to_string(delay_s));
  }
  node_delay_s_[v.index()] = delay_s;
}

void CostOverlay::set_turn_delay(EdgeId in, EdgeId out, double delay_s) {
  for (EdgeId e : {in, out}) {
    if (!e.valid() || e.index() >= edges_.size()) {
      throw CostUpdateError("unknown edge id " + std::to_string(e.v) + " (the map has " + std::to_string(edges_.size()) +
                            " edges)");
    }
  }
  const NodeId at = graph_->head(in);
  if (graph_->tail(out) != at) {
    throw CostUpdateError("edges " + std::to_string(in.v) + " and " + std::to_string(out.v) +
                          " do not meet: no movement from one onto the other");
  }
  if (!(delay_s >= 0.0) || !std::isfinite(delay_s)) {
    throw CostUpdateError("movement delay must be a finite number of seconds >= 0, got " + std::to_string(delay_s));
  }
  if (turn_row_.empty()) {
    turn_row_.assign(edges_.size(), 0);
    first_out_at_head_.assign(edges_.size(), 0);
  }
  const auto outs = graph_->out_edges(at);
  const std::uint32_t first = (*outs.begin()).v;
  if (turn_row_[in.index()] == 0) {
    turn_row_[in.index()] = static_cast<std::uint32_t>(turn_delay_s_.size()) + 1;
    first_out_at_head_[in.index()] = first;
    turn_delay_s_.resize(turn_delay_s_.size() + outs.size(), 0.0);
  }
  turn_delay_s_[turn_row_[in.index()] - 1 + (out.v - first)] = delay_s;
}

void CostOverlay::set_signal_delay(const maps::RoadGraph& graph, double delay_s) {
  for (NodeId v : graph.nodes()) {
    if (graph.signalized(v)) set_node_delay(v, delay_s);
  }
}

}  // namespace corridor::planner
