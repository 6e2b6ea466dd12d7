#include "planner/cost_overlay.hpp"

#include <cmath>
#include <string>

#include "planner/cost.hpp"

namespace corridor::planner {

CostOverlay::CostOverlay(const maps::RoadGraph& graph)
    : edges_(graph.edge_count()), node_delay_s_(graph.node_count(), 0.0) {}

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

void CostOverlay::set_signal_delay(const maps::RoadGraph& graph, double delay_s) {
  for (NodeId v : graph.nodes()) {
    if (graph.signalized(v)) set_node_delay(v, delay_s);
  }
}

}  // namespace corridor::planner
