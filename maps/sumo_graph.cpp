#include "maps/sumo_graph.hpp"

#include <algorithm>
#include <map>
#include <numeric>
#include <optional>

#include "maps/errors.hpp"

namespace corridor::maps {
namespace {

bool drivable(const SumoEdge& e, SumoClasses cls) { return (e.function.empty() || e.function == "normal") && e.admits(cls); }

// The lane whose length, speed and shape stand for the edge: the first the class may use.
const SumoLane& lane_for(const SumoEdge& e, SumoClasses cls) {
  for (const SumoLane& l : e.lanes) {
    if ((l.allowed & cls) != 0) return l;
  }
  return e.lanes.front();
}

struct Arc {
  NodeId tail;
  NodeId head;
  const SumoEdge* onto;
};

}  // namespace

std::span<const EdgeId> SumoGraph::arcs(const std::string& sumo_edge) const {
  const auto it = arcs_onto.find(sumo_edge);
  if (it == arcs_onto.end()) return {};
  return it->second;
}

SumoGraph build_sumo_graph(const SumoNet& net, std::string_view vehicle_class) {
  const std::optional<SumoClasses> cls = sumo_class_bit(vehicle_class);
  if (!cls) throw MapLoadError("'" + std::string(vehicle_class) + "' is not a SUMO vehicle class (for example emergency, passenger, bus)");
  std::vector<const SumoEdge*> edges;
  for (const SumoEdge& e : net.edges) {
    if (drivable(e, *cls)) edges.push_back(&e);
  }
  if (edges.empty()) {
    throw MapLoadError("the SUMO network has no normal edge a vehicle of class '" + std::string(vehicle_class) + "' may drive on");
  }

  RoadGraphData d;
  d.origin = {0.0, 0.0};  // the net's own metric frame; SUMO runs need no geographic position
  std::vector<std::string> node_edge;
  std::unordered_map<std::string, NodeId> stop_line;
  auto add_node = [&](const SumoEdge& e, Point2 p) {
    const NodeId v{static_cast<std::uint32_t>(node_edge.size())};
    node_edge.push_back(e.id);
    d.node_x_m.push_back(p.x_m);
    d.node_y_m.push_back(p.y_m);
    d.node_osm_id.push_back(OsmNodeId{static_cast<std::int64_t>(v.v + 1)});
    const SumoJunction* j = net.junction(e.to);
    d.node_signalized.push_back(j != nullptr && j->type.find("traffic_light") != std::string::npos ? 1 : 0);
    return v;
  };
  for (const SumoEdge* e : edges) {
    const auto& shape = lane_for(*e, *cls).shape;
    const Point2 end = shape.empty() ? Point2{} : shape.back();
    stop_line.emplace(e->id, add_node(*e, end));
  }

  std::vector<Arc> arcs;
  std::map<std::pair<std::string, std::string>, bool> seen;  // one arc per edge pair, whatever the lanes
  std::unordered_map<std::string, bool> has_predecessor;
  for (const SumoConnection& c : net.connections) {
    const auto from = stop_line.find(c.from);
    const auto to = stop_line.find(c.to);
    if (from == stop_line.end() || to == stop_line.end()) continue;  // internal or non-drivable edges
    if (!net.admits(c, *cls)) continue;  // a lane or a turn this class may not take
    if (!seen.emplace(std::make_pair(c.from, c.to), true).second) continue;
    arcs.push_back({from->second, to->second, net.edge(c.to)});
    has_predecessor[c.to] = true;
  }
  for (const SumoEdge* e : edges) {
    if (has_predecessor.contains(e->id)) continue;
    const auto& shape = lane_for(*e, *cls).shape;
    const NodeId entry = add_node(*e, shape.empty() ? Point2{} : shape.front());
    d.node_signalized.back() = 0;
    arcs.push_back({entry, stop_line.at(e->id), e});
  }
  std::stable_sort(arcs.begin(), arcs.end(), [](const Arc& a, const Arc& b) { return a.tail < b.tail; });

  std::vector<std::string> sumo_edge_of_arc;
  std::unordered_map<std::string, std::vector<EdgeId>> arcs_onto;
  d.first_out.assign(node_edge.size() + 1, 0);
  d.geometry_first.push_back(0);
  std::map<std::pair<NodeId, NodeId>, EdgeId> by_ends;
  for (const Arc& a : arcs) {
    const EdgeId id{static_cast<std::uint32_t>(sumo_edge_of_arc.size())};
    ++d.first_out[a.tail.index() + 1];
    d.edge_tail.push_back(a.tail);
    d.edge_head.push_back(a.head);
    double speed = 0.0;
    for (const SumoLane& l : a.onto->lanes) {
      if ((l.allowed & *cls) != 0) speed = std::max(speed, l.speed_mps);
    }
    const SumoLane& lane = lane_for(*a.onto, *cls);
    d.edge_length_m.push_back(std::max(0.1, lane.length_m));
    d.edge_speed_mps.push_back(static_cast<float>(std::max(speed, 0.1)));
    d.edge_osm_way.push_back(OsmWayId{static_cast<std::int64_t>(id.v + 1)});
    d.edge_class.push_back(RoadClass::primary);
    // From the previous stop line over the junction onto the edge, to its own stop line.
    d.geometry.push_back({d.node_x_m[a.tail.index()], d.node_y_m[a.tail.index()]});
    for (const Point2& p : lane.shape) d.geometry.push_back(p);
    if (d.geometry.size() - d.geometry_first.back() < 2) d.geometry.push_back({d.node_x_m[a.head.index()], d.node_y_m[a.head.index()]});
    d.geometry_first.push_back(static_cast<std::uint32_t>(d.geometry.size()));
    by_ends.emplace(std::make_pair(a.tail, a.head), id);
    sumo_edge_of_arc.push_back(a.onto->id);
    arcs_onto[a.onto->id].push_back(id);
  }
  std::partial_sum(d.first_out.begin(), d.first_out.end(), d.first_out.begin());
  d.edge_twin.assign(arcs.size(), kInvalidEdge);
  for (std::size_t i = 0; i < arcs.size(); ++i) {
    const auto it = by_ends.find({arcs[i].head, arcs[i].tail});
    if (it != by_ends.end()) d.edge_twin[i] = it->second;
  }
  build_reverse_adjacency(d);
  d.turns_in_edges = {1};  // a graph edge is a SUMO connection: every turn in the graph is one SUMO allows
  return SumoGraph{RoadGraph(std::move(d)), *cls, std::move(sumo_edge_of_arc), std::move(node_edge), std::move(arcs_onto),
                   std::move(stop_line)};
}

std::unordered_map<NodeId, SignalPlan> plans_by_node(const SumoGraph& graph, const SumoNet& /*net*/,
                                                     const std::vector<SumoSignalPlan>& plans,
                                                     std::unordered_map<NodeId, std::size_t>* tls_of) {
  std::unordered_map<NodeId, SignalPlan> out;
  for (std::size_t i = 0; i < plans.size(); ++i) {
    const SumoSignalPlan& sp = plans[i];
    std::vector<EdgeId> movement_edge(sp.links.size(), kInvalidEdge);
    std::vector<NodeId> approaches;
    for (std::size_t k = 0; k < sp.links.size(); ++k) {
      const SumoConnection* c = sp.links[k];
      if (c == nullptr) continue;
      const auto from = graph.stop_line.find(c->from);
      if (from == graph.stop_line.end()) continue;
      for (EdgeId arc : graph.graph.out_edges(from->second)) {
        if (graph.sumo_edge_of_arc[arc.index()] == c->to) movement_edge[k] = arc;
      }
      if (std::find(approaches.begin(), approaches.end(), from->second) == approaches.end()) approaches.push_back(from->second);
    }
    // Links that leave from one lane share its queue.
    std::vector<std::vector<std::size_t>> lane_mates(sp.links.size());
    for (std::size_t k = 0; k < sp.links.size(); ++k) {
      for (std::size_t j = 0; j < sp.links.size(); ++j) {
        const SumoConnection* a = sp.links[k];
        const SumoConnection* b = sp.links[j];
        if (j != k && a != nullptr && b != nullptr && a->from == b->from && a->from_lane == b->from_lane) lane_mates[k].push_back(j);
      }
    }
    for (NodeId node : approaches) {
      if (out.contains(node)) continue;
      SignalPlan plan = sp.plan;
      plan.node = node;
      plan.movement_edge = movement_edge;
      plan.lane_mates = lane_mates;
      out.emplace(node, std::move(plan));
      if (tls_of != nullptr) (*tls_of)[node] = i;
    }
  }
  return out;
}

SignalMap sumo_signal_map(const SumoGraph& graph, const SumoNet& net, const std::vector<SumoSignalPlan>& plans,
                          std::unordered_map<NodeId, std::size_t>* tls_of_out) {
  SignalMap m;
  std::unordered_map<NodeId, std::size_t> tls_of;
  m.plans = plans_by_node(graph, net, plans, &tls_of);
  std::map<std::size_t, NodeId> key_of_tls;
  for (const auto& [node, index] : tls_of) {
    auto [it, fresh] = key_of_tls.emplace(index, node);
    if (!fresh && node < it->second) it->second = node;
  }
  for (const auto& [node, index] : tls_of) m.signal_of[node] = key_of_tls.at(index);
  for (const auto& [index, key] : key_of_tls) {
    SignalPlan plan = m.plans.at(key);
    plan.node = key;
    m.signals.emplace(key, std::move(plan));
    m.names.emplace(key, plans[index].tls_id);
  }
  if (tls_of_out != nullptr) *tls_of_out = std::move(tls_of);
  return m;
}

}  // namespace corridor::maps
