#include "localizer/match/path_smoother.hpp"

#include "localizer/match/corner_cut.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <tuple>
#include <unordered_map>

namespace corridor::localizer {
namespace {

// The chain's path as edge occurrences, each with the path distance at its offset 0.
struct Occurrence {
  EdgeId edge;
  double s_start;
};

// The distance the fixes' speeds say the vehicle drove from fix a to fix b (the trapezoid rule),
// or NaN when a fix between them has no speed, or two of them lie more than speed_gap_s apart
// (over a tunnel's minute, two speeds say nothing of where the vehicle stopped or sped up).
double driven_m(std::span<const GpsFix> fixes, std::size_t a, std::size_t b, double speed_gap_s) {
  double sum = 0.0;
  for (std::size_t i = a; i < b; ++i) {
    if (!fixes[i].speed_mps || !fixes[i + 1].speed_mps || fixes[i + 1].time_s - fixes[i].time_s > speed_gap_s) {
      return std::numeric_limits<double>::quiet_NaN();
    }
    sum += 0.5 * (*fixes[i].speed_mps + *fixes[i + 1].speed_mps) * std::max(0.0, fixes[i + 1].time_s - fixes[i].time_s);
  }
  return sum;
}

// The distance a vehicle drives along a matched path, against the path's own distance s along the
// road's centre lines. A vehicle rounds each corner on an arc instead of running to the vertex and
// turning there, and keeps to its side of a two-way road, so it drives less than the centre lines
// through a turn, more so through a turn to its side (corner_cut.hpp). The receiver's speeds measure the driven
// distance u; the fixes' projections measure s. u(s) is piecewise linear (each vertex's difference
// spread over the arc), increasing, and inverted by bisection over its breakpoints.
class DrivenCoordinate {
 public:
  DrivenCoordinate(const maps::RoadGraph& g, const std::vector<Occurrence>& path, const CornerModel& corner) {
    struct Vertex {
      maps::Point2 p;
      double s;
      double offset;  // the lane offset on the segment that ends here
    };
    std::vector<Vertex> v;
    for (const Occurrence& o : path) {
      const auto pts = g.geometry(o.edge);
      double geometric = 0.0;
      for (std::size_t i = 1; i < pts.size(); ++i) geometric += maps::distance_m(pts[i - 1], pts[i]);
      const double scale = geometric > 0.0 ? g.length_m(o.edge) / geometric : 1.0;
      const double offset = g.twin(o.edge).valid() ? corner.lane_offset_m : 0.0;
      double at = o.s_start;
      if (v.empty()) v.push_back({pts.front(), at, offset});
      for (std::size_t i = 1; i < pts.size(); ++i) {
        at += maps::distance_m(pts[i - 1], pts[i]) * scale;
        if (at - v.back().s < 0.05) continue;
        v.push_back({pts[i], at, offset});
      }
    }
    struct Ramp {
      double from, to, delta;
    };
    std::vector<Ramp> ramps;
    for (std::size_t j = 1; j + 1 < v.size(); ++j) {
      const double theta = turn_towards_traffic_side_rad(g, v[j].p.x_m - v[j - 1].p.x_m, v[j].p.y_m - v[j - 1].p.y_m,
                                                         v[j + 1].p.x_m - v[j].p.x_m, v[j + 1].p.y_m - v[j].p.y_m);
      const CornerCut cut = corner_cut(theta, v[j].s - v[j - 1].s, v[j + 1].s - v[j].s, corner.radius_m,
                                       0.5 * (v[j].offset + v[j + 1].offset));
      if (cut.saving_m == 0.0) continue;
      ramps.push_back({v[j].s - cut.half_width_m, v[j].s + cut.half_width_m, cut.saving_m});
    }
    // u falls behind s by each ramp's share as the ramps pass: a sweep over their ends, each piece
    // between two ends linear with slope 1 minus the ramps under it (kept above 0.05, increasing).
    std::vector<std::pair<double, double>> ends;  // (s, change of the falling slope there)
    for (const Ramp& r : ramps) {
      const double slope = r.delta / (r.to - r.from);
      ends.emplace_back(r.from, slope), ends.emplace_back(r.to, -slope);
    }
    std::sort(ends.begin(), ends.end());
    s_.assign(1, path.front().s_start - 1e6);
    u_.assign(1, s_.front());
    double falling = 0.0;
    for (const auto& [at, change] : ends) {
      if (at > s_.back()) {
        u_.push_back(u_.back() + (at - s_.back()) * std::max(0.05, 1.0 - falling));
        s_.push_back(at);
      }
      falling += change;
    }
    const double end = path.back().s_start + g.length_m(path.back().edge) + 1e6;
    u_.push_back(u_.back() + (end - s_.back()) * std::max(0.05, 1.0 - falling));
    s_.push_back(end);
  }
  [[nodiscard]] double to_u(double s) const { return interpolate(s_, u_, s); }
  [[nodiscard]] double to_s(double u) const { return interpolate(u_, s_, u); }

 private:
  static double interpolate(const std::vector<double>& x, const std::vector<double>& y, double at) {
    auto it = std::upper_bound(x.begin(), x.end(), at);
    if (it == x.begin()) return y.front() + (at - x.front());
    if (it == x.end()) return y.back() + (at - x.back());
    const std::size_t k = static_cast<std::size_t>(it - x.begin());
    const double span = x[k] - x[k - 1];
    return span > 0.0 ? y[k - 1] + (y[k] - y[k - 1]) * (at - x[k - 1]) / span : y[k];
  }
  std::vector<double> s_, u_;
};

// Takes out of the path every loop (a node it comes back to) that the vehicle did not drive. Where
// fixes scatter over a small roundabout, or over both ways of a road at a stop, the most likely
// sequence of edges may run once more round the loop: each move round it is only a few σ longer
// than the noisy fixes say, but the whole loop's length is never paid back, and the filter would
// then spread it over the fixes on both sides (tens of metres along the road at σ 15 m). The
// fixes' speeds tell: between the last matched point before the loop and the first after it the
// vehicle drove `driven` metres, the path with the loop is `with` long and without it `with − L`;
// the loop goes where `driven` is nearer the shorter, and where every fix matched on it lies
// within 3σ of the edge into or out of its node, which then takes it. A fix further off says the
// vehicle was out there, whatever the speeds say. Without speeds, the path is kept as matched, and
// so is a loop at the very start of the chain (no matched point before it to measure from).
void erase_undriven_loops(const maps::RoadGraph& g, std::span<const GpsFix> fixes, const SmootherConfig& config,
                          std::vector<MatchedPoint>& points, std::vector<Occurrence>& path, std::vector<double>& s,
                          std::vector<std::size_t>& occurrence) {
  const std::size_t n = points.size();
  struct Move {
    std::size_t point;
    bool into;  // onto the edge into the loop's node, else the one out of it
    maps::RoadGraph::EdgePoint at;
  };
  std::vector<Move> moves;
  std::size_t from = 1;
  while (true) {
    // The first loop at or after `from`: occurrences [j, k) leave node v and k starts from it again.
    std::size_t j = 0, k = 0;
    // Keyed by node: a chain's path has tens of nodes, and a graph-sized array per chain would cost
    // more than the hash map.
    std::unordered_map<std::uint32_t, std::size_t> seen;
    for (std::size_t o = 0; o < path.size() && k == 0; ++o) {
      const auto [it, fresh] = seen.try_emplace(g.tail(path[o].edge).v, o);
      if (!fresh && o >= from) j = it->second, k = o;
      it->second = o;
    }
    if (k == 0) return;
    from = k + 1;
    // The last matched point before the loop and the first after it. A loop taken out earlier may
    // have left its fixes on the edges into and out of its node in either order, so `before` is
    // the point before the first one on or past the loop.
    std::size_t a = n, b = n;
    bool reached = false;  // a point on or past the loop seen
    for (std::size_t i = 0; i < n && b == n; ++i) {
      if (!points[i].matched) continue;
      if (occurrence[i] >= k) b = i;
      if (occurrence[i] >= j) {
        reached = true;
      } else if (!reached) {
        a = i;
      }
    }
    if (a == n || b == n) continue;  // so j ≥ 1: an edge leads into the loop's node
    const double loop = path[k].s_start - path[j].s_start;
    const double driven = driven_m(fixes, a, b, config.speed_gap_s);
    if (!(driven < s[b] - s[a] - 0.5 * loop)) continue;
    moves.clear();
    bool near = true;
    for (std::size_t i = a + 1; i < b && near; ++i) {
      if (!points[i].matched || occurrence[i] < j) continue;
      const maps::Point2 raw = g.projection().to_local(fixes[i].position);
      const auto out = g.nearest_point(path[k].edge, raw);
      const auto in = g.nearest_point(path[j - 1].edge, raw);
      // Each fix to the nearer: the filter weighs them by time and speed after, and forcing the
      // order (once one is out, all are) cost Porto 0.05–0.08 points of edge share.
      const bool into = in.distance_m < out.distance_m;
      moves.push_back({i, into, into ? in : out});
      near = moves.back().at.distance_m <= 3.0 * usable_hdop(fixes[i], config.default_hdop) * config.sigma_base_m;
    }
    if (!near) continue;
    // The loop goes: its fixes move to the road into or out of the node, and everything after it
    // comes `loop` metres nearer along the path.
    const std::size_t removed = k - j;
    const double out_start = path[j].s_start;  // where the edge out of v starts once the loop is out
    for (const Move& m : moves) {
      MatchedPoint& p = points[m.point];
      p.edge = path[m.into ? j - 1 : k].edge;
      p.offset_m = m.at.offset_m;
      p.point = m.at.point;
      occurrence[m.point] = m.into ? j - 1 : j;
      s[m.point] = (m.into ? path[j - 1].s_start : out_start) + m.at.offset_m;
    }
    for (std::size_t i = b; i < n; ++i) {
      if (!points[i].matched || occurrence[i] < k) continue;
      occurrence[i] -= removed;
      s[i] -= loop;
    }
    for (std::size_t o = k; o < path.size(); ++o) path[o].s_start -= loop;
    path.erase(path.begin() + static_cast<std::ptrdiff_t>(j), path.begin() + static_cast<std::ptrdiff_t>(k));
    from = j;
  }
}

}  // namespace

std::vector<MatchedPoint> smooth_along_path(const maps::RoadGraph& g, planner::BoundedDistances& distances,
                                            std::span<const GpsFix> fixes, std::span<const MatchedPoint> points,
                                            const SmootherConfig& config) {
  std::vector<MatchedPoint> out(points.begin(), points.end());
  const std::size_t n = points.size();
  if (n < 3 || fixes.size() != n || !points.front().matched || !points.back().matched) return out;

  // 1. The path and each matched point's distance along it (NaN for a point without a match: an
  // outlier the matcher set aside, placed by the filter alone).
  std::vector<Occurrence> path{{points[0].edge, 0.0}};
  std::vector<double> s(n, std::numeric_limits<double>::quiet_NaN());
  std::vector<std::size_t> occurrence(n, 0);  // a matched point's edge's place in `path`
  s[0] = points[0].offset_m;
  std::size_t last = 0;  // the last matched point
  for (std::size_t i = 1; i < n; ++i) {
    const MatchedPoint& a = points[last];
    const MatchedPoint& b = points[i];
    if (!b.matched) continue;
    if (b.edge == a.edge && b.edge == path.back().edge) {
      s[i] = path.back().s_start + b.offset_m;  // along the same edge (a little back is noise)
      occurrence[i] = path.size() - 1;
    } else {
      distances.run(g, g.head(path.back().edge), 5000.0, std::array<NodeId, 1>{g.tail(b.edge)});
      if (distances.length_m(g.tail(b.edge)) == planner::kInfCost) return out;
      double at = path.back().s_start + g.length_m(path.back().edge);
      for (EdgeId e : distances.path_to(g, g.tail(b.edge))) {
        path.push_back({e, at});
        at += g.length_m(e);
      }
      path.push_back({b.edge, at});
      s[i] = at + b.offset_m;
      occurrence[i] = path.size() - 1;
    }
    last = i;
  }
  erase_undriven_loops(g, fixes, config, out, path, s, occurrence);
  // A path much longer than the fixes moved (a loop round a block where noise put a fix behind
  // the last one) would drag the estimate along it: the chain is smoothed in two parts there.
  // NaN from driven_m (no speeds) compares false: only the first rule applies.
  auto sigma_of = [&](const GpsFix& f) { return usable_hdop(f, config.default_hdop) * config.sigma_base_m; };
  std::size_t before_last = 0;  // the matched point before `last`
  last = 0;
  for (std::size_t i = 1; i < n; ++i) {
    if (!points[i].matched) continue;
    const double dt = std::max(1.0, fixes[i].time_s - fixes[last].time_s);
    const double moved = maps::distance_m(out[last].point, out[i].point);  // loops taken out
    // A move the speeds say the vehicle did not drive (the match went round a road our graph
    // lacks) splits it too, beyond what two noisy positions along the path allow, where the
    // points on either side agree among themselves: the point before `last` with it, the point
    // after `i` with `i`. One fix that far off alone is a multipath outlier, which the filter
    // weighs down; so is a chain's first or last point, with nothing to agree with. Both need the
    // speeds: without them (NaN) two points neither disagree nor agree.
    auto misfit = [&](std::size_t from, std::size_t to) {
      const double noise = 3.0 * std::sqrt(2.0) * std::max(sigma_of(fixes[from]), sigma_of(fixes[to])) + 10.0;
      return std::abs(s[to] - s[from] - driven_m(fixes, from, to, config.speed_gap_s)) - noise;  // > 0 off, ≤ 0 agree, NaN neither
    };
    std::size_t next = i + 1;
    while (next < n && !points[next].matched) ++next;
    const bool detour = last > 0 && i + 1 < n && misfit(last, i) > 0.0 && misfit(last, next) > 0.0 &&
                        misfit(i, next) <= 0.0 && misfit(before_last, last) <= 0.0;
    if (std::abs(s[i] - s[last]) > 2.0 * moved + 10.0 * dt || detour) {
      auto head = smooth_along_path(g, distances, fixes.first(last + 1), points.first(last + 1), config);
      const auto tail = smooth_along_path(g, distances, fixes.subspan(i), points.subspan(i), config);
      // The path between the two parts is in doubt, but the vehicle was somewhere between the
      // edge one ends on and the edge the other starts on: a fix set aside between them goes to the
      // nearer of the two where it lies within 3σ of it (a turn through a junction our graph draws
      // elsewhere, where SUMO's vehicle cut across); further off, it keeps no estimate.
      // On the first edge it goes no further back than the first part's end, on the second no
      // further on than the second part's start: a multipath fix thrown along the road is not
      // followed there either.
      const EdgeId before_gap = head.back().edge, after_gap = tail.front().edge;
      for (std::size_t k = last + 1; k < i; ++k) {
        MatchedPoint m = points[k];
        const maps::Point2 raw = g.projection().to_local(fixes[k].position);
        auto on = [&](EdgeId e, double from_m, double to_m) {
          const double offset = std::clamp(g.nearest_point(e, raw).offset_m, from_m, std::max(from_m, to_m));
          const maps::Point2 p = g.point_along(e, offset);
          return std::tuple{maps::distance_m(p, raw), offset, p};
        };
        const auto a = on(before_gap, head.back().offset_m, g.length_m(before_gap));
        const auto b = on(after_gap, 0.0, tail.front().offset_m);
        const bool to_before = std::get<0>(a) <= std::get<0>(b);
        const auto& [distance, offset, point] = to_before ? a : b;
        if (distance <= 3.0 * sigma_of(fixes[k])) {
          m.matched = true;
          m.edge = to_before ? before_gap : after_gap;
          m.offset_m = offset;
          m.point = point;
        }
        head.push_back(m);
      }
      head.insert(head.end(), tail.begin(), tail.end());
      return head;
    }
    before_last = last;
    last = i;
  }

  // 2. Constant-velocity Kalman filter over (u, v), the driven distance, then the RTS smoother.
  const DrivenCoordinate driven(g, path, config.corner);
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isnan(s[i])) s[i] = driven.to_u(s[i]);
  }
  using Vec = std::array<double, 2>;
  using Mat = std::array<double, 4>;  // row-major 2×2
  std::vector<Vec> xf(n), xp(n);
  std::vector<Mat> pf(n), pp(n);
  const double q = config.acceleration_sigma * config.acceleration_sigma;
  auto sigma_s = [&](std::size_t i) {
    return usable_hdop(fixes[i], config.default_hdop) * config.sigma_base_m;
  };
  std::size_t second = 1;  // the first matched point after the start
  while (!points[second].matched) ++second;
  const double v0 = fixes[0].speed_mps.value_or(fixes[second].time_s > fixes[0].time_s
                                                    ? (s[second] - s[0]) / (fixes[second].time_s - fixes[0].time_s)
                                                    : 0.0);
  xf[0] = {s[0], v0};
  pf[0] = {std::pow(sigma_s(0), 2), 0.0, 0.0, fixes[0].speed_mps ? std::pow(config.speed_sigma_mps, 2) : 25.0};
  xp[0] = xf[0];
  pp[0] = pf[0];
  for (std::size_t i = 1; i < n; ++i) {
    const double dt = std::max(0.0, fixes[i].time_s - fixes[i - 1].time_s);
    const Vec& x = xf[i - 1];
    const Mat& p = pf[i - 1];
    // Predict: x = F x, P = F P Fᵀ + Q.
    Vec x1{x[0] + dt * x[1], x[1]};
    Mat p1{p[0] + dt * (p[2] + p[1]) + dt * dt * p[3] + q * dt * dt * dt / 3.0, p[1] + dt * p[3] + q * dt * dt / 2.0,
           p[2] + dt * p[3] + q * dt * dt / 2.0, p[3] + q * dt};
    xp[i] = x1;
    pp[i] = p1;
    // Update with the position along the path, then with the speed if the fix has one.
    auto update = [&](int row, double z, double r) {
      const double hx = x1[static_cast<std::size_t>(row)];
      const double s_var = p1[static_cast<std::size_t>(row * 3)] + r;  // P[row][row] + R
      const double k0 = p1[static_cast<std::size_t>(row)] / s_var;     // P[0][row] / S
      const double k1 = p1[static_cast<std::size_t>(2 + row)] / s_var; // P[1][row] / S
      const double innovation = z - hx;
      x1 = {x1[0] + k0 * innovation, x1[1] + k1 * innovation};
      const double pr0 = p1[static_cast<std::size_t>(row * 2)], pr1 = p1[static_cast<std::size_t>(row * 2 + 1)];  // row of P
      p1 = {p1[0] - k0 * pr0, p1[1] - k0 * pr1, p1[2] - k1 * pr0, p1[3] - k1 * pr1};
    };
    if (points[i].matched) {
      update(0, s[i], std::pow(sigma_s(i), 2));
      if (fixes[i].speed_mps) update(1, *fixes[i].speed_mps, std::pow(config.speed_sigma_mps, 2));
    }
    xf[i] = x1;
    pf[i] = p1;
  }
  std::vector<Vec> xs(xf);
  for (std::size_t i = n - 1; i-- > 0;) {
    const double dt = std::max(0.0, fixes[i + 1].time_s - fixes[i].time_s);
    const Mat& p = pf[i];
    const Mat& pn = pp[i + 1];
    // C = P_f Fᵀ P_pred⁻¹
    const Mat pft{p[0] + dt * p[1], p[1], p[2] + dt * p[3], p[3]};  // P Fᵀ
    const double det = pn[0] * pn[3] - pn[1] * pn[2];
    if (!(std::abs(det) > 1e-12)) continue;
    const Mat inv{pn[3] / det, -pn[1] / det, -pn[2] / det, pn[0] / det};
    const Mat c{pft[0] * inv[0] + pft[1] * inv[2], pft[0] * inv[1] + pft[1] * inv[3], pft[2] * inv[0] + pft[3] * inv[2],
                pft[2] * inv[1] + pft[3] * inv[3]};
    const Vec d{xs[i + 1][0] - xp[i + 1][0], xs[i + 1][1] - xp[i + 1][1]};
    xs[i] = {xf[i][0] + c[0] * d[0] + c[1] * d[1], xf[i][1] + c[2] * d[0] + c[3] * d[1]};
  }

  // 3. Back onto the path.
  const double s_end = path.back().s_start + g.length_m(path.back().edge);
  for (std::size_t i = 0; i < n; ++i) {
    const double at = std::clamp(driven.to_s(xs[i][0]), 0.0, s_end);
    auto it = std::upper_bound(path.begin(), path.end(), at, [](double v, const Occurrence& o) { return v < o.s_start; });
    const Occurrence& o = it == path.begin() ? path.front() : *std::prev(it);
    out[i].edge = o.edge;
    out[i].offset_m = std::clamp(at - o.s_start, 0.0, g.length_m(o.edge));
    out[i].point = g.point_along(o.edge, out[i].offset_m);
    out[i].matched = true;
  }
  return out;
}

}  // namespace corridor::localizer
