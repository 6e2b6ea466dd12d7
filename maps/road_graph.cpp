#include "maps/road_graph.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "maps/errors.hpp"
#include "maps/strongly_connected.hpp"

namespace corridor::maps {
namespace {

void require(bool ok, const char* what) {
  if (!ok) throw MapError(std::string("inconsistent road graph: ") + what);
}

void validate(const RoadGraphData& d) {
  const std::size_t n = d.node_x_m.size();
  const std::size_t m = d.edge_head.size();
  require(n < std::numeric_limits<std::uint32_t>::max() && m < std::numeric_limits<std::uint32_t>::max(),
          "too many nodes or edges for 32-bit ids");
  require(d.node_y_m.size() == n && d.node_osm_id.size() == n && d.node_signalized.size() == n,
          "node arrays differ in length");
  require(d.first_out.size() == n + 1 && d.first_in.size() == n + 1, "CSR offsets have the wrong length");
  require(d.edge_tail.size() == m && d.edge_length_m.size() == m && d.edge_speed_mps.size() == m &&
              d.edge_osm_way.size() == m && d.edge_class.size() == m && d.edge_twin.size() == m &&
              d.in_edge.size() == m && d.geometry_first.size() == m + 1,
          "edge arrays differ in length");
  require(d.edge_name.size() == m && d.edge_ref.size() == m, "name arrays differ in length");
  require(!d.strings.first.empty() && d.strings.first.front() == 0 && d.strings.first.back() == d.strings.chars.size(),
          "string table offsets do not cover its characters");
  for (std::size_t i = 0; i + 1 < d.strings.first.size(); ++i) {
    require(d.strings.first[i] <= d.strings.first[i + 1], "string table offsets decrease");
  }
  for (std::size_t e = 0; e < m; ++e) {
    require(d.edge_name[e] < d.strings.size() && d.edge_ref[e] < d.strings.size(), "edge name id out of range");
  }
  require(d.first_out.front() == 0 && d.first_out.back() == m, "forward CSR does not cover all edges");
  require(d.first_in.front() == 0 && d.first_in.back() == m, "reverse CSR does not cover all edges");
  require(d.geometry_first.front() == 0 && d.geometry_first.back() == d.geometry.size(),
          "geometry offsets do not cover the geometry");
  for (std::size_t u = 0; u < n; ++u) {
    require(d.first_out[u] <= d.first_out[u + 1] && d.first_in[u] <= d.first_in[u + 1], "CSR offsets decrease");
    require(std::isfinite(d.node_x_m[u]) && std::isfinite(d.node_y_m[u]), "node coordinate is not finite");
    for (auto e = d.first_out[u]; e < d.first_out[u + 1]; ++e) {
      require(d.edge_tail[e].index() == u, "edge tail disagrees with the forward CSR");
    }
    for (auto i = d.first_in[u]; i < d.first_in[u + 1]; ++i) {
      require(d.in_edge[i].index() < m && d.edge_head[d.in_edge[i].index()].index() == u,
              "edge head disagrees with the reverse CSR");
    }
  }
  for (std::size_t i = 0; i < d.edge_limits.size(); ++i) {
    const EdgeLimit& l = d.edge_limits[i];
    require(l.edge.index() < m && (i == 0 || d.edge_limits[i - 1].edge < l.edge), "edge limits unsorted or out of range");
    require(std::isfinite(l.max_height_m) && std::isfinite(l.max_width_m) && std::isfinite(l.max_weight_t) &&
                l.max_height_m >= 0 && l.max_width_m >= 0 && l.max_weight_t >= 0,
            "edge limit is not a finite non-negative number");
  }
  require(d.node_stop.empty() || d.node_stop.size() == n, "barrier stops do not cover the nodes");
  require(std::all_of(d.node_stop.begin(), d.node_stop.end(), [](std::uint8_t s) { return s <= 1; }), "barrier stop flag is not 0 or 1");
  for (std::size_t i = 0; i < d.roundabout_edges.size(); ++i) {
    require(d.roundabout_edges[i].index() < m && (i == 0 || d.roundabout_edges[i - 1] < d.roundabout_edges[i]),
            "roundabout edges unsorted or out of range");
  }
  const TurnRestrictions& r = d.restrictions;
  require(r.first.size() == r.size() + 1 && r.mode.size() == r.size() && r.except.size() == r.size() &&
              r.first.front() == 0 && r.first.back() == r.edges.size(),
          "turn restriction arrays differ in length");
  for (std::size_t i = 0; i < r.size(); ++i) {
    require(r.first[i + 1] >= r.first[i] && r.first[i + 1] - r.first[i] >= 2, "a turn restriction needs a from and a to edge");
    require(r.mode[i] <= static_cast<std::uint8_t>(RestrictionMode::hgv), "unknown turn restriction mode");
    require(r.except[i] < (1u << kVehicleClassCount), "unknown vehicle class in a turn restriction's except");
  }
  for (std::size_t i = 0; i < r.size(); ++i) {
    for (auto j = r.first[i]; j < r.first[i + 1]; ++j) {
      require(r.edges[j].index() < m, "turn restriction edge out of range");
      require(j == r.first[i] || d.edge_tail[r.edges[j].index()] == d.edge_head[r.edges[j - 1].index()],
              "turn restriction edges do not follow each other");
    }
  }
  require(d.turns_in_edges.size() <= 1 && d.left_hand_traffic.size() <= 1, "traffic rule flags have the wrong size");
  const std::size_t k = d.landmarks.nodes.size();
  require(k <= 256 && d.landmarks.from_ticks.size() == n * k && d.landmarks.to_ticks.size() == n * k,
          "landmark tables have the wrong size");
  for (NodeId l : d.landmarks.nodes) require(l.index() < n, "landmark out of range");
  for (std::size_t e = 0; e < m; ++e) {
    require(d.edge_head[e].index() < n, "edge head out of range");
    require(std::isfinite(d.edge_length_m[e]) && d.edge_length_m[e] > 0.0, "edge length must be positive");
    require(std::isfinite(d.edge_speed_mps[e]) && d.edge_speed_mps[e] > 0.0f, "edge speed must be positive");
    require(!d.edge_twin[e].valid() || d.edge_twin[e].index() < m, "edge twin out of range");
    require(d.geometry_first[e] + 2 <= d.geometry_first[e + 1], "edge geometry needs at least two points");
  }
}

}  // namespace

bool continues_way_at_stop(const RoadGraphData& d, EdgeId in, EdgeId out) {
  return !d.node_stop.empty() && d.node_stop[d.edge_head[in.index()].index()] != 0 && out != d.edge_twin[in.index()] &&
         d.edge_osm_way[out.index()] == d.edge_osm_way[in.index()];
}

void build_reverse_adjacency(RoadGraphData& d) {
  const std::size_t n = d.node_x_m.size();
  d.first_in.assign(n + 1, 0);
  for (NodeId v : d.edge_head) ++d.first_in[v.index() + 1];
  for (std::size_t v = 0; v < n; ++v) d.first_in[v + 1] += d.first_in[v];
  d.in_edge.assign(d.edge_head.size(), kInvalidEdge);
  std::vector<std::uint32_t> fill(d.first_in.begin(), d.first_in.end() - 1);
  for (std::uint32_t e = 0; e < d.edge_head.size(); ++e) d.in_edge[fill[d.edge_head[e].index()]++] = EdgeId{e};
}

RoadGraph::RoadGraph(RoadGraphData data) : data_(std::move(data)), projection_(data_.origin) {
  if (data_.edge_name.empty()) data_.edge_name.assign(data_.edge_head.size(), 0);
  if (data_.edge_ref.empty()) data_.edge_ref.assign(data_.edge_head.size(), 0);
  if (data_.strings.first.empty()) data_.strings.first = {0, 0};
  validate(data_);
  {
    // Derived, not stored: Tarjan takes a few milliseconds on a metro area.
    std::vector<std::uint32_t> heads(edge_count());
    for (EdgeId e : edges()) heads[e.index()] = head(e).v;
    const Components c = strongly_connected_components(data_.first_out, heads);
    main_component_.assign(node_count(), 0);
    for (NodeId u : nodes()) main_component_[u.index()] = c.component_of[u.index()] == c.largest ? 1 : 0;
    main_component_nodes_ = node_count() > 0 ? c.largest_size : 0;
    runner_up_component_nodes_ = node_count() > 0 ? c.runner_up_size : 0;
    component_count_ = c.count;
  }
  // Landmarks on the main component only (maps/landmarks.hpp says why).
  if (data_.landmarks.nodes.empty()) data_.landmarks = compute_landmarks(data_, kDefaultLandmarkCount, main_component_);
  turns_ = TurnGraph(data_);

  if (node_count() > 0) {
    min_corner_ = max_corner_ = position(NodeId{0});
    for (const Point2& p : data_.geometry) {
      min_corner_ = {std::min(min_corner_.x_m, p.x_m), std::min(min_corner_.y_m, p.y_m)};
      max_corner_ = {std::max(max_corner_.x_m, p.x_m), std::max(max_corner_.y_m, p.y_m)};
    }
  }
}

Point2 RoadGraph::point_along(EdgeId e, double offset_m) const {
  const auto pts = geometry(e);
  double geometric = 0.0;
  for (std::size_t i = 1; i < pts.size(); ++i) geometric += distance_m(pts[i - 1], pts[i]);
  // Offsets are in units of the edge's stated length; geometry may be drawn shorter or longer.
  double remaining = std::clamp(offset_m, 0.0, length_m(e)) * (geometric / length_m(e));
  for (std::size_t i = 1; i < pts.size(); ++i) {
    const double seg = distance_m(pts[i - 1], pts[i]);
    if (remaining <= seg && seg > 0.0) {
      const double t = remaining / seg;
      return {pts[i - 1].x_m + t * (pts[i].x_m - pts[i - 1].x_m), pts[i - 1].y_m + t * (pts[i].y_m - pts[i - 1].y_m)};
    }
    remaining -= seg;
  }
  return pts.back();
}

RoadGraph::EdgePoint RoadGraph::nearest_point(EdgeId e, Point2 p) const {
  const auto pts = geometry(e);
  EdgePoint best;
  best.point = pts.front();
  best.distance_m = distance_m(p, pts.front());
  double along = 0.0, best_along = 0.0;
  for (std::size_t i = 1; i < pts.size(); ++i) {
    const double seg = distance_m(pts[i - 1], pts[i]);
    const double t = segment_fraction(p, pts[i - 1], pts[i]);
    const Point2 q{pts[i - 1].x_m + t * (pts[i].x_m - pts[i - 1].x_m), pts[i - 1].y_m + t * (pts[i].y_m - pts[i - 1].y_m)};
    const double d = distance_m(p, q);
    if (d < best.distance_m) {
      best.point = q;
      best.distance_m = d;
      best_along = along + t * seg;
    }
    along += seg;
  }
  // Offsets are in units of the edge's stated length (point_along's rule).
  best.offset_m = along > 0.0 ? std::clamp(best_along * length_m(e) / along, 0.0, length_m(e)) : 0.0;
  return best;
}

}  // namespace corridor::maps
