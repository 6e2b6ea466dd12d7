#include "maps/graph_builder.hpp"

#include <algorithm>
#include <numeric>
#include <stdexcept>

#include "maps/errors.hpp"
#include "maps/strongly_connected.hpp"

namespace corridor::maps {
namespace {

// Edges shorter than this are stretched to it, so that every travel time is positive and path
// extraction can never cycle through zero-cost edges.
constexpr double kMinEdgeLengthM = 0.1;

struct DirectedEdge {
  std::uint32_t tail;
  std::uint32_t head;
  std::uint32_t segment;
  bool reversed;
  std::uint32_t twin;  // index in the directed-edge list, or max
};

// Position along a Hilbert curve over a 2^16 x 2^16 grid. Numbering nodes in this order puts
// nodes that are near on the map near in memory, so a search's g values, heap positions and
// adjacency come in cache lines it has just touched; at city scale every search is bound by memory
// latency more than by arithmetic.
std::uint64_t hilbert_index(std::uint32_t x, std::uint32_t y) {
  constexpr std::uint32_t kSide = 1u << 16;
  std::uint64_t d = 0;
  for (std::uint32_t s = kSide / 2; s > 0; s /= 2) {
    const std::uint32_t rx = (x & s) != 0 ? 1 : 0;
    const std::uint32_t ry = (y & s) != 0 ? 1 : 0;
    d += std::uint64_t{s} * s * ((3 * rx) ^ ry);
    if (ry == 0) {  // rotate the quadrant so the curve stays continuous
      if (rx == 1) {
        x = kSide - 1 - x;
        y = kSide - 1 - y;
      }
      std::swap(x, y);
    }
  }
  return d;
}

double polyline_length(const std::vector<Point2>& pts, std::uint32_t first, std::uint32_t last) {
  double len = 0.0;
  for (std::uint32_t i = first + 1; i <= last; ++i) len += distance_m(pts[i - 1], pts[i]);
  return len;
}

}  // namespace

RoadGraph build_road_graph(const GraphBuildInput& in, GraphBuildReport* report, const GraphBuildOptions& options) {
  constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
  const auto n_in = static_cast<std::uint32_t>(in.node_pos.size());
  if (in.node_signalized.size() != n_in || (!in.node_stop.empty() && in.node_stop.size() != n_in)) {
    throw std::invalid_argument("build_road_graph: per-node arrays differ in length from the node positions");
  }

  std::vector<DirectedEdge> edges;
  edges.reserve(in.segments.size() * 2);
  for (std::uint32_t s = 0; s < in.segments.size(); ++s) {
    const RoadSegment& seg = in.segments[s];
    if (seg.from == seg.to) continue;  // a loop back to the same intersection never shortens a route
    std::uint32_t fwd = kNone;
    if (seg.forward) {
      fwd = static_cast<std::uint32_t>(edges.size());
      edges.push_back({seg.from, seg.to, s, false, kNone});
    }
    if (seg.backward) {
      const auto bwd = static_cast<std::uint32_t>(edges.size());
      edges.push_back({seg.to, seg.from, s, true, fwd});
      if (fwd != kNone) edges[fwd].twin = bwd;
    }
  }

  // Every road is kept, including a one-way street that leaves the extract and a car park's roads
  // that join no public road (a route may start or end there); a node with no drivable road at all
  // is dropped. RoadGraph finds the components and marks the largest as the main one, which
  // snapping can prefer (planner/snap_points.hpp). A generated network keeps only that one.
  std::vector<std::uint8_t> keep(n_in, 0);
  if (options.main_component_only) {
    std::vector<std::uint32_t> first_out(n_in + 1, 0), heads(edges.size());
    for (const auto& e : edges) ++first_out[e.tail + 1];
    std::partial_sum(first_out.begin(), first_out.end(), first_out.begin());
    std::vector<std::uint32_t> fill(first_out.begin(), first_out.end() - 1);
    for (const auto& e : edges) heads[fill[e.tail]++] = e.head;
    const Components comps = strongly_connected_components(first_out, heads);
    for (std::uint32_t u = 0; u < n_in; ++u) keep[u] = comps.component_of[u] == comps.largest ? 1 : 0;
  } else {
    for (const auto& e : edges) keep[e.tail] = keep[e.head] = 1;
  }
  std::vector<std::uint32_t> new_id(n_in, kNone);
  RoadGraphData d;
  d.origin = in.origin;
  d.strings = in.strings;
  std::vector<std::uint32_t> members;
  for (std::uint32_t u = 0; u < n_in; ++u) {
    if (keep[u] != 0) members.push_back(u);
  }
  if (!members.empty()) {
    Point2 lo = in.node_pos[members.front()];
    Point2 hi = lo;
    for (std::uint32_t u : members) {
      lo = {std::min(lo.x_m, in.node_pos[u].x_m), std::min(lo.y_m, in.node_pos[u].y_m)};
      hi = {std::max(hi.x_m, in.node_pos[u].x_m), std::max(hi.y_m, in.node_pos[u].y_m)};
    }
    const double span = std::max({hi.x_m - lo.x_m, hi.y_m - lo.y_m, 1.0});
    auto cell = [&](double v, double low) {
      return static_cast<std::uint32_t>(std::clamp((v - low) / span * 65535.0, 0.0, 65535.0));
    };
    std::vector<std::uint64_t> key(n_in, 0);
    for (std::uint32_t u : members) key[u] = hilbert_index(cell(in.node_pos[u].x_m, lo.x_m), cell(in.node_pos[u].y_m, lo.y_m));
    std::stable_sort(members.begin(), members.end(), [&](std::uint32_t a, std::uint32_t b) { return key[a] < key[b]; });
  }
  std::uint32_t kept = 0;
  for (std::uint32_t u : members) {
    new_id[u] = kept++;
    d.node_x_m.push_back(in.node_pos[u].x_m);
    d.node_y_m.push_back(in.node_pos[u].y_m);
    d.node_osm_id.push_back(in.node_osm[u]);
    d.node_signalized.push_back(in.node_signalized[u]);
    if (!in.node_stop.empty()) d.node_stop.push_back(in.node_stop[u]);
  }
  if (std::find(d.node_stop.begin(), d.node_stop.end(), std::uint8_t{1}) == d.node_stop.end()) d.node_stop.clear();

  // Every edge, ordered by new tail (stable, so twins stay deterministic).
  std::vector<std::uint32_t> order;
  for (std::uint32_t i = 0; i < edges.size(); ++i) {
    if (new_id[edges[i].tail] != kNone && new_id[edges[i].head] != kNone) order.push_back(i);
  }
  std::stable_sort(order.begin(), order.end(),
                   [&](std::uint32_t a, std::uint32_t b) { return new_id[edges[a].tail] < new_id[edges[b].tail]; });
  std::vector<std::uint32_t> new_edge(edges.size(), kNone);
  for (std::uint32_t i = 0; i < order.size(); ++i) new_edge[order[i]] = i;

  if (order.empty()) throw MapLoadError("the map contains no drivable road");

  d.first_out.assign(kept + 1, 0);
  d.geometry_first.push_back(0);
  for (std::uint32_t old : order) {
    const DirectedEdge& e = edges[old];
    const RoadSegment& seg = in.segments[e.segment];
    ++d.first_out[new_id[e.tail] + 1];
    d.edge_tail.push_back(NodeId{new_id[e.tail]});
    d.edge_head.push_back(NodeId{new_id[e.head]});
    d.edge_length_m.push_back(std::max(kMinEdgeLengthM, polyline_length(in.points, seg.first_point, seg.last_point)));
    d.edge_speed_mps.push_back(e.reversed ? seg.backward_speed_mps : seg.forward_speed_mps);
    d.edge_osm_way.push_back(seg.way);
    d.edge_class.push_back(seg.road_class);
    d.edge_name.push_back(seg.name);
    d.edge_ref.push_back(seg.ref);
    if (seg.roundabout) d.roundabout_edges.push_back(EdgeId{static_cast<std::uint32_t>(d.edge_head.size() - 1)});
    if (seg.max_height_m > 0 || seg.max_width_m > 0 || seg.max_weight_t > 0) {
      d.edge_limits.push_back({EdgeId{static_cast<std::uint32_t>(d.edge_head.size() - 1)}, seg.max_height_m,
                               seg.max_width_m, seg.max_weight_t});
    }
    d.edge_twin.push_back(e.twin != kNone && new_edge[e.twin] != kNone ? EdgeId{new_edge[e.twin]} : kInvalidEdge);
    if (e.reversed) {
      for (std::uint32_t p = seg.last_point + 1; p-- > seg.first_point;) d.geometry.push_back(in.points[p]);
    } else {
      for (std::uint32_t p = seg.first_point; p <= seg.last_point; ++p) d.geometry.push_back(in.points[p]);
    }
    d.geometry_first.push_back(static_cast<std::uint32_t>(d.geometry.size()));
  }
  std::partial_sum(d.first_out.begin(), d.first_out.end(), d.first_out.begin());
  build_reverse_adjacency(d);

  const std::size_t signalized =
      static_cast<std::size_t>(std::count(d.node_signalized.begin(), d.node_signalized.end(), std::uint8_t{1}));
  RoadGraph graph(std::move(d));
  if (report != nullptr) {
    report->input_nodes = n_in;
    report->kept_nodes = kept;
    report->dropped_nodes = n_in - kept;
    report->kept_edges = order.size();
    report->components = graph.component_count();
    report->largest_component_nodes = graph.main_component_nodes();
    report->signalized_nodes = signalized;
  }
  return graph;
}

}  // namespace corridor::maps
