#include "maps/synthetic_grid.hpp"

#include <random>

#include "maps/graph_builder.hpp"

namespace corridor::maps {

RoadGraph make_perturbed_grid(const GridSpec& spec) {
  std::mt19937_64 rng(spec.seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  GraphBuildInput in;
  in.origin = spec.origin;
  const double jitter = spec.jitter_fraction * spec.spacing_m / 2.0;
  for (std::uint32_t r = 0; r < spec.rows; ++r) {
    for (std::uint32_t c = 0; c < spec.cols; ++c) {
      in.node_pos.push_back({c * spec.spacing_m + (2 * unit(rng) - 1) * jitter,
                             r * spec.spacing_m + (2 * unit(rng) - 1) * jitter});
      in.node_osm.push_back(OsmNodeId{static_cast<std::int64_t>(r) * spec.cols + c + 1});
      in.node_signalized.push_back(unit(rng) < spec.signal_fraction ? 1 : 0);
    }
  }
  std::int64_t way = 1;
  auto add = [&](std::uint32_t a, std::uint32_t b) {
    if (unit(rng) < spec.removal_fraction) return;
    RoadSegment s;
    s.from = a;
    s.to = b;
    s.first_point = static_cast<std::uint32_t>(in.points.size());
    in.points.push_back(in.node_pos[a]);
    // A bent midpoint, so edges carry real polylines and length exceeds the chord.
    const Point2 pa = in.node_pos[a], pb = in.node_pos[b];
    in.points.push_back({(pa.x_m + pb.x_m) / 2 + (unit(rng) - 0.5) * jitter * 0.5,
                         (pa.y_m + pb.y_m) / 2 + (unit(rng) - 0.5) * jitter * 0.5});
    in.points.push_back(pb);
    s.last_point = static_cast<std::uint32_t>(in.points.size() - 1);
    if (unit(rng) < spec.oneway_fraction) {
      const bool fwd = unit(rng) < 0.5;
      s.forward = fwd;
      s.backward = !fwd;
    }
    const auto speed = static_cast<float>((spec.min_speed_kmh + unit(rng) * (spec.max_speed_kmh - spec.min_speed_kmh)) / 3.6);
    s.forward_speed_mps = s.backward_speed_mps = speed;
    s.way = OsmWayId{way++};
    s.road_class = RoadClass::synthetic;
    in.segments.push_back(s);
  };
  for (std::uint32_t r = 0; r < spec.rows; ++r) {
    for (std::uint32_t c = 0; c < spec.cols; ++c) {
      const std::uint32_t u = r * spec.cols + c;
      if (c + 1 < spec.cols) add(u, u + 1);
      if (r + 1 < spec.rows) add(u, u + spec.cols);
      if (c + 1 < spec.cols && r + 1 < spec.rows && unit(rng) < spec.diagonal_fraction) add(u, u + spec.cols + 1);
    }
  }
  return build_road_graph(in, nullptr, GraphBuildOptions{.main_component_only = true});
}

}  // namespace corridor::maps
