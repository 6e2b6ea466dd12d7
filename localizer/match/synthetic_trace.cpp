#include "localizer/match/synthetic_trace.hpp"

#include <cmath>
#include <numbers>
#include <random>

namespace corridor::localizer {

SyntheticTrace make_synthetic_trace(const maps::RoadGraph& g, const SyntheticTraceSpec& spec) {
  std::mt19937_64 rng(spec.seed);
  std::normal_distribution<double> noise(0.0, spec.noise_sigma_m);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<EdgeId> walk;
  // The walk starts on the main component, where it can go on at every junction but a dead end.
  EdgeId e{static_cast<std::uint32_t>(rng() % g.edge_count())};
  for (int draw = 0; draw < 1000 && !g.in_main_component(e); ++draw) e = EdgeId{static_cast<std::uint32_t>(rng() % g.edge_count())};
  for (std::size_t k = 0; k < spec.edges; ++k) {
    walk.push_back(e);
    std::vector<EdgeId> next;
    for (EdgeId o : g.out_edges(g.head(e))) {
      if (o != g.twin(e)) next.push_back(o);
    }
    if (next.empty()) break;
    e = next[rng() % next.size()];
  }
  SyntheticTrace out;
  const double step = spec.speed_mps * spec.period_s;
  double t = 0.0, along = step / 2.0;
  for (EdgeId w : walk) {
    for (; along < g.length_m(w); along += step, t += spec.period_s) {
      const maps::Point2 p = g.point_along(w, along);
      maps::Point2 q{p.x_m + noise(rng), p.y_m + noise(rng)};
      if (unit(rng) < spec.outlier_share) {
        const double a = unit(rng) * 2.0 * std::numbers::pi;
        q = {q.x_m + spec.outlier_m * std::cos(a), q.y_m + spec.outlier_m * std::sin(a)};
      }
      GpsFix f;
      f.time_s = t;
      f.position = g.projection().to_lat_lon(q);
      f.hdop = std::max(1.0, spec.noise_sigma_m / 4.0);
      out.fixes.push_back(f);
      out.truth.push_back(w);
      out.truth_point.push_back(p);
    }
    along -= g.length_m(w);
  }
  return out;
}

}  // namespace corridor::localizer
