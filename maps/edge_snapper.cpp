#include "maps/edge_snapper.hpp"

#include <algorithm>
#include <cmath>
#include <boost/geometry.hpp>
#include <boost/geometry/index/rtree.hpp>
#include <sstream>
#include <vector>

#include "maps/errors.hpp"

namespace corridor::maps {

namespace bg = boost::geometry;
namespace bgi = boost::geometry::index;

using BgPoint = bg::model::point<double, 2, bg::cs::cartesian>;
using BgSegment = bg::model::segment<BgPoint>;

struct EdgeSnapper::Index {
  struct Piece {
    EdgeId edge;
    double start_along_m;  // geometric distance from the edge's tail to this piece's start
  };
  std::vector<Piece> pieces;
  std::vector<double> geometric_length_m;  // per edge
  bgi::rtree<std::pair<BgSegment, std::uint32_t>, bgi::rstar<16>> tree;
};

EdgeSnapper::EdgeSnapper(const RoadGraph& graph) : graph_(graph), index_(std::make_unique<Index>()) {
  std::vector<std::pair<BgSegment, std::uint32_t>> values;
  index_->geometric_length_m.assign(graph.edge_count(), 0.0);
  for (EdgeId e : graph.edges()) {
    const auto pts = graph.geometry(e);
    double along = 0.0;
    // Twins share their geometry; index the road once and report both directions.
    const bool indexed = !graph.twin(e).valid() || e < graph.twin(e);
    for (std::size_t i = 1; i < pts.size(); ++i) {
      if (indexed) {
        values.emplace_back(BgSegment{{pts[i - 1].x_m, pts[i - 1].y_m}, {pts[i].x_m, pts[i].y_m}},
                            static_cast<std::uint32_t>(index_->pieces.size()));
        index_->pieces.push_back({e, along});
      }
      along += distance_m(pts[i - 1], pts[i]);
    }
    index_->geometric_length_m[e.index()] = along;
  }
  index_->tree = decltype(index_->tree)(values.begin(), values.end());  // bulk loading packs the tree
}

EdgeSnapper::~EdgeSnapper() = default;

SnapResult EdgeSnapper::snap(LatLon p, const SnapOptions& options) const {
  if (!is_valid_lat_lon(p)) {
    std::ostringstream msg;
    msg << "invalid coordinate (" << p.lat_deg << ", " << p.lon_deg
        << "): latitude must be within [-90, 90] and longitude within [-180, 180]";
    throw SnapError(SnapError::Reason::invalid_coordinate, msg.str());
  }
  try {
    return snap_local(graph_.projection().to_local(p), options);
  } catch (const SnapError& e) {
    if (e.reason() != SnapError::Reason::outside_map) throw;
    std::ostringstream msg;
    const LatLon lo = graph_.projection().to_lat_lon(graph_.min_corner());
    const LatLon hi = graph_.projection().to_lat_lon(graph_.max_corner());
    msg.precision(7);
    msg << "coordinate (" << p.lat_deg << ", " << p.lon_deg << ") is outside the map, which covers lat " << lo.lat_deg
        << ".." << hi.lat_deg << ", lon " << lo.lon_deg << ".." << hi.lon_deg;
    throw SnapError(SnapError::Reason::outside_map, msg.str());
  }
}

std::vector<SnapResult> EdgeSnapper::candidates_local(Point2 p, double radius_m, std::size_t max_count) const {
  std::vector<SnapResult> out;
  if (!std::isfinite(p.x_m) || !std::isfinite(p.y_m) || !(radius_m > 0.0) || max_count == 0) return out;
  const bg::model::box<BgPoint> box{{p.x_m - radius_m, p.y_m - radius_m}, {p.x_m + radius_m, p.y_m + radius_m}};
  thread_local std::vector<std::pair<BgSegment, std::uint32_t>> found;
  found.clear();
  index_->tree.query(bgi::intersects(box), std::back_inserter(found));
  for (const auto& [segment, piece_id] : found) {
    const auto& piece = index_->pieces[piece_id];
    const Point2 a{bg::get<0, 0>(segment), bg::get<0, 1>(segment)};
    const Point2 b{bg::get<1, 0>(segment), bg::get<1, 1>(segment)};
    const double t = segment_fraction(p, a, b);
    const Point2 q{a.x_m + t * (b.x_m - a.x_m), a.y_m + t * (b.y_m - a.y_m)};
    const double d = distance_m(p, q);
    if (d > radius_m) continue;
    // One result per road: keep its nearest piece.
    auto same = std::find_if(out.begin(), out.end(), [&](const SnapResult& r) { return r.edge == piece.edge; });
    if (same != out.end() && same->distance_m <= d) continue;
    SnapResult r;
    r.edge = piece.edge;
    r.point = q;
    r.distance_m = d;
    const double geometric = index_->geometric_length_m[r.edge.index()];
    const double length = graph_.length_m(r.edge);
    const double along = piece.start_along_m + t * distance_m(a, b);
    r.offset_m = geometric > 0.0 ? std::clamp(along * length / geometric, 0.0, length) : 0.0;
    r.twin = graph_.twin(r.edge);
    if (r.twin.valid()) r.twin_offset_m = graph_.twin_offset_m(r.edge, r.offset_m);
    if (same != out.end()) {
      *same = r;
    } else {
      out.push_back(r);
    }
  }
  std::sort(out.begin(), out.end(), [](const SnapResult& x, const SnapResult& y) { return x.distance_m < y.distance_m; });
  if (out.size() > max_count) out.resize(max_count);
  return out;
}

SnapResult EdgeSnapper::snap_local(Point2 p, const SnapOptions& options) const {
  const double margin = options.max_distance_m;
  if (!std::isfinite(p.x_m) || !std::isfinite(p.y_m) || p.x_m < graph_.min_corner().x_m - margin ||
      p.x_m > graph_.max_corner().x_m + margin || p.y_m < graph_.min_corner().y_m - margin ||
      p.y_m > graph_.max_corner().y_m + margin) {
    throw SnapError(SnapError::Reason::outside_map, "coordinate is outside the map");
  }
  std::vector<std::pair<BgSegment, std::uint32_t>> found;
  if (options.main_component_only || options.skip_ferries) {
    const auto wanted = [&](const std::pair<BgSegment, std::uint32_t>& v) {
      const EdgeId e = index_->pieces[v.second].edge;
      return (!options.main_component_only || graph_.in_main_component(e)) &&
             (!options.skip_ferries || !graph_.is_ferry(e));
    };
    index_->tree.query(bgi::nearest(BgPoint{p.x_m, p.y_m}, 1) && bgi::satisfies(wanted), std::back_inserter(found));
  } else {
    index_->tree.query(bgi::nearest(BgPoint{p.x_m, p.y_m}, 1), std::back_inserter(found));
  }
  if (found.empty()) {
    throw SnapError(SnapError::Reason::outside_map,
                    options.main_component_only ? "the map's main component has no roads"
                    : options.skip_ferries      ? "the map has no roads but ferries"
                                                : "the map has no roads");
  }

  const auto& [segment, piece_id] = found.front();
  const auto& piece = index_->pieces[piece_id];
  const Point2 a{bg::get<0, 0>(segment), bg::get<0, 1>(segment)};
  const Point2 b{bg::get<1, 0>(segment), bg::get<1, 1>(segment)};
  const double dx = b.x_m - a.x_m, dy = b.y_m - a.y_m;
  const double t = segment_fraction(p, a, b);

  SnapResult r;
  r.edge = piece.edge;
  r.point = {a.x_m + t * dx, a.y_m + t * dy};
  r.distance_m = distance_m(p, r.point);
  if (r.distance_m > options.max_distance_m) {
    std::ostringstream msg;
    msg.precision(1);
    msg << std::fixed << "no drivable road within " << options.max_distance_m << " m of the coordinate (nearest is "
        << r.distance_m << " m away)";
    throw SnapError(SnapError::Reason::too_far_from_road, msg.str());
  }
  const double geometric = index_->geometric_length_m[r.edge.index()];
  const double along = piece.start_along_m + t * std::sqrt(dx * dx + dy * dy);
  const double length = graph_.length_m(r.edge);
  r.offset_m = geometric > 0.0 ? std::clamp(along * length / geometric, 0.0, length) : 0.0;
  r.twin = graph_.twin(r.edge);
  if (r.twin.valid()) r.twin_offset_m = graph_.twin_offset_m(r.edge, r.offset_m);
  return r;
}

}  // namespace corridor::maps
