// The immutable road graph: forward and reverse adjacency as CSR arrays, with per-edge attributes
// and geometry in the map's local metric frame.
#pragma once

#include <algorithm>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "maps/geo.hpp"
#include "maps/ids.hpp"
#include "maps/landmarks.hpp"
#include "maps/road_class.hpp"
#include "maps/string_table.hpp"
#include "maps/turn_graph.hpp"
#include "maps/turn_restriction.hpp"

namespace corridor::maps {

// What a road allows through: 0 where no limit is tagged.
struct EdgeLimit {
  EdgeId edge;
  float max_height_m = 0;
  float max_width_m = 0;
  float max_weight_t = 0;
};

// Plain arrays, as built by the importer and as stored in the cache. RoadGraph validates them once.
struct RoadGraphData {
  LatLon origin;  // centre of the local projection

  // Per node.
  std::vector<double> node_x_m;
  std::vector<double> node_y_m;
  std::vector<OsmNodeId> node_osm_id;
  std::vector<std::uint8_t> node_signalized;  // 1 when the intersection has traffic signals

  // Forward CSR: the out-edges of node u are [first_out[u], first_out[u+1]).
  std::vector<std::uint32_t> first_out;
  std::vector<NodeId> edge_tail;
  std::vector<NodeId> edge_head;
  std::vector<double> edge_length_m;
  std::vector<float> edge_speed_mps;  // legal / free-flow speed
  std::vector<OsmWayId> edge_osm_way;
  std::vector<RoadClass> edge_class;
  std::vector<EdgeId> edge_twin;  // the same road in the opposite direction, or invalid
  // OSM `name` and `ref` of the edge's way, as ids into `strings` (0: none). May be left empty by a
  // builder that has no names (synthetic grids); the graph then fills them with 0.
  std::vector<std::uint32_t> edge_name;
  std::vector<std::uint32_t> edge_ref;
  StringTable strings;

  // Geometry: edge e's polyline is geometry[geometry_first[e] .. geometry_first[e+1]), tail to head.
  std::vector<std::uint32_t> geometry_first;
  std::vector<Point2> geometry;

  // Reverse CSR: the in-edges of node v are in_edge[first_in[v] .. first_in[v+1]).
  std::vector<std::uint32_t> first_in;
  std::vector<EdgeId> in_edge;

  // ALT landmark tables (maps/landmarks.hpp). Left empty by builders; RoadGraph computes them.
  LandmarkTables landmarks;

  // Physical limits (maxheight, maxwidth, maxweight, height restrictors on the road), sorted by
  // edge; only the few edges that have one. A vehicle profile decides which bind.
  std::vector<EdgeLimit> edge_limits;
  // Edges on a roundabout (junction=roundabout|circular), sorted; for "take exit N" steps.
  std::vector<EdgeId> roundabout_edges;
  // Per node, 1 where a barrier stands that the vehicle passes but stops at (a gate, a toll booth;
  // maps::node_stops_vehicle). The importer makes each such node a graph node of its own, so the
  // delay is charged exactly as a signal's is: once for each route through the node. Empty when the
  // map has none.
  std::vector<std::uint8_t> node_stop;

  // Turn restrictions on the edges (maps/turn_restriction.hpp); empty where the source has none.
  TurnRestrictions restrictions;
  // {1} when the edges already encode the allowed turns (a SUMO net's connections, or an abstract
  // graph of links such as the seed's hand-made ones): every turn in the graph is then legal and
  // free. Empty or {0} for a road network with turns at its nodes.
  std::vector<std::uint8_t> turns_in_edges;
  // {1} where traffic keeps left (a right turn then crosses oncoming traffic). Empty or {0}: right.
  std::vector<std::uint8_t> left_hand_traffic;
};

// Whether going from edge `in` onto edge `out`, at in's head, goes on along the same way through a
// barrier the vehicle stops at (RoadGraphData::node_stop), not back. Such a node is a node only to
// charge the barrier's delay: no turn is made there, whatever the bend. The turn graph gives the
// move no angle and the route's steps no maneuver.
bool continues_way_at_stop(const RoadGraphData& data, EdgeId in, EdgeId out);

class RoadGraph {
 public:
  // Throws MapError when the arrays are inconsistent (for example, a corrupt cache).
  explicit RoadGraph(RoadGraphData data);

  [[nodiscard]] std::size_t node_count() const { return data_.node_x_m.size(); }
  [[nodiscard]] std::size_t edge_count() const { return data_.edge_head.size(); }
  [[nodiscard]] IdRange<NodeId> nodes() const { return {0, static_cast<std::uint32_t>(node_count())}; }
  [[nodiscard]] IdRange<EdgeId> edges() const { return {0, static_cast<std::uint32_t>(edge_count())}; }

  [[nodiscard]] IdRange<EdgeId> out_edges(NodeId u) const {
    return {data_.first_out[u.index()], data_.first_out[u.index() + 1]};
  }
  [[nodiscard]] std::span<const EdgeId> in_edges(NodeId v) const {
    return {data_.in_edge.data() + data_.first_in[v.index()], data_.first_in[v.index() + 1] - data_.first_in[v.index()]};
  }

  [[nodiscard]] NodeId tail(EdgeId e) const { return data_.edge_tail[e.index()]; }
  [[nodiscard]] NodeId head(EdgeId e) const { return data_.edge_head[e.index()]; }
  [[nodiscard]] double length_m(EdgeId e) const { return data_.edge_length_m[e.index()]; }
  [[nodiscard]] double speed_mps(EdgeId e) const { return data_.edge_speed_mps[e.index()]; }
  [[nodiscard]] OsmWayId osm_way(EdgeId e) const { return data_.edge_osm_way[e.index()]; }
  [[nodiscard]] RoadClass road_class(EdgeId e) const { return data_.edge_class[e.index()]; }
  // A ferry or shuttle train: the vehicle rides it (trips do not start or end on one).
  [[nodiscard]] bool is_ferry(EdgeId e) const { return road_class(e) == RoadClass::ferry; }
  [[nodiscard]] EdgeId twin(EdgeId e) const { return data_.edge_twin[e.index()]; }
  // The place `offset_m` along e, measured along its twin (which must exist): the same share of the
  // way from the other end, since the two directions of a road may differ in length (a SUMO net's
  // lanes do). Clamped onto the twin.
  [[nodiscard]] double twin_offset_m(EdgeId e, double offset_m) const {
    const double len = length_m(e);
    const double twin_len = length_m(twin(e));
    const double share = len > 0.0 ? offset_m / len : 0.0;
    return std::clamp(twin_len * (1.0 - share), 0.0, twin_len);
  }
  // The street's OSM name and ref ("" when the way has none).
  [[nodiscard]] std::string_view name(EdgeId e) const { return data_.strings.at(data_.edge_name[e.index()]); }
  [[nodiscard]] std::string_view ref(EdgeId e) const { return data_.strings.at(data_.edge_ref[e.index()]); }
  [[nodiscard]] std::span<const Point2> geometry(EdgeId e) const {
    const auto b = data_.geometry_first[e.index()];
    return {data_.geometry.data() + b, data_.geometry_first[e.index() + 1] - b};
  }

  [[nodiscard]] Point2 position(NodeId u) const { return {data_.node_x_m[u.index()], data_.node_y_m[u.index()]}; }
  [[nodiscard]] OsmNodeId osm_node(NodeId u) const { return data_.node_osm_id[u.index()]; }
  [[nodiscard]] bool signalized(NodeId u) const { return data_.node_signalized[u.index()] != 0; }

  // The point at `offset_m` along edge e (clamped to the edge).
  [[nodiscard]] Point2 point_along(EdgeId e, double offset_m) const;
  // The nearest point of edge e to p: its offset (in the edge's length units, as point_along
  // takes it), the point, and its distance from p.
  struct EdgePoint {
    double offset_m = 0.0;
    Point2 point;
    double distance_m = 0.0;
  };
  [[nodiscard]] EdgePoint nearest_point(EdgeId e, Point2 p) const;

  [[nodiscard]] const LocalProjection& projection() const { return projection_; }
  [[nodiscard]] const RoadGraphData& data() const { return data_; }
  // The arrays back, to build a changed graph from them (the importer adds restrictions this way).
  [[nodiscard]] RoadGraphData take_data() && { return std::move(data_); }

  // ALT: a lower bound in seconds on the free-flow travel time from a to b, exactly consistent
  // (maps/landmarks.hpp). Every travel cost the planner charges is at least free flow.
  [[nodiscard]] std::size_t landmark_count() const { return data_.landmarks.nodes.size(); }
  [[nodiscard]] std::span<const std::uint32_t> landmarks_from(NodeId v) const {
    return {data_.landmarks.from_ticks.data() + v.index() * landmark_count(), landmark_count()};
  }
  [[nodiscard]] std::span<const std::uint32_t> landmarks_to(NodeId v) const {
    return {data_.landmarks.to_ticks.data() + v.index() * landmark_count(), landmark_count()};
  }
  [[nodiscard]] double landmark_bound_s(NodeId a, NodeId b) const {
    return static_cast<double>(landmark_bound_ticks(landmarks_from(a), landmarks_to(a), landmarks_from(b), landmarks_to(b))) *
           kLandmarkTickS;
  }

  [[nodiscard]] std::span<const EdgeLimit> edge_limits() const { return data_.edge_limits; }
  // Whether a barrier the vehicle stops at (a gate, a toll booth) stands on node v.
  [[nodiscard]] bool has_stops() const { return !data_.node_stop.empty(); }
  [[nodiscard]] bool stop_at(NodeId v) const { return has_stops() && data_.node_stop[v.index()] != 0; }
  [[nodiscard]] bool continues_way_at_stop(EdgeId in, EdgeId out) const { return maps::continues_way_at_stop(data_, in, out); }
  [[nodiscard]] bool on_roundabout(EdgeId e) const {
    return std::binary_search(data_.roundabout_edges.begin(), data_.roundabout_edges.end(), e);
  }

  // The map's main component: its largest strongly connected part, where every node reaches every
  // other. The importer keeps the rest as well (a one-way street that leaves the extract, a car
  // park's service roads that join no public road): a route may start or end there, and a snap
  // may prefer the main component when the nearest road is cut off (planner/snap_points.hpp).
  [[nodiscard]] bool in_main_component(NodeId u) const { return main_component_[u.index()] != 0; }
  [[nodiscard]] bool in_main_component(EdgeId e) const { return in_main_component(tail(e)) && in_main_component(head(e)); }
  [[nodiscard]] std::size_t main_component_nodes() const { return main_component_nodes_; }
  // The nodes of the next largest component: equal to the main one's when the largest is a tie.
  [[nodiscard]] std::size_t runner_up_component_nodes() const { return runner_up_component_nodes_; }
  [[nodiscard]] std::size_t component_count() const { return component_count_; }

  // The edge-based graph searches run on: turns, their angles and the restrictions on them.
  [[nodiscard]] const TurnGraph& turns() const { return turns_; }
  [[nodiscard]] bool left_hand_traffic() const {
    return !data_.left_hand_traffic.empty() && data_.left_hand_traffic.front() != 0;
  }

  // Bounding box in the local frame.
  [[nodiscard]] Point2 min_corner() const { return min_corner_; }
  [[nodiscard]] Point2 max_corner() const { return max_corner_; }

 private:
  RoadGraphData data_;
  LocalProjection projection_;
  TurnGraph turns_;
  std::vector<std::uint8_t> main_component_;  // per node: 1 in the largest strongly connected part
  std::size_t main_component_nodes_ = 0;
  std::size_t runner_up_component_nodes_ = 0;
  std::size_t component_count_ = 0;
  Point2 min_corner_;
  Point2 max_corner_;
};

// Fills first_in / in_edge from the forward arrays.
void build_reverse_adjacency(RoadGraphData& data);

}  // namespace corridor::maps
