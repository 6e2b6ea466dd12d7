#include "maps/turn_graph.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <string>

#include "maps/errors.hpp"
#include "maps/road_graph.hpp"

namespace corridor::maps {
namespace {

double bearing_deg(Point2 a, Point2 b) { return std::atan2(b.x_m - a.x_m, b.y_m - a.y_m) * 180.0 / std::numbers::pi; }

// A turn while the graph is built (`other` is its target, which may still be redirected to a copy).
using Arc = TurnArc;

}  // namespace

double leaving_bearing_deg(std::span<const Point2> pts) {
  for (std::size_t i = 1; i < pts.size(); ++i) {
    if (distance_m(pts[0], pts[i]) > 0.05) return bearing_deg(pts[0], pts[i]);
  }
  return bearing_deg(pts.front(), pts.back());
}

double arriving_bearing_deg(std::span<const Point2> pts) {
  for (std::size_t i = pts.size() - 1; i-- > 0;) {
    if (distance_m(pts[i], pts.back()) > 0.05) return bearing_deg(pts[i], pts.back());
  }
  return bearing_deg(pts.front(), pts.back());
}

double signed_turn_deg(double from_bearing_deg, double to_bearing_deg) {
  double d = std::fmod(to_bearing_deg - from_bearing_deg, 360.0);
  if (d <= -180.0) d += 360.0;
  if (d > 180.0) d -= 360.0;
  return d;
}

TurnGraph::TurnGraph(const RoadGraphData& d) : edge_count_(d.edge_head.size()) {
  const std::size_t m = edge_count_;
  const bool turns_in_edges = !d.turns_in_edges.empty() && d.turns_in_edges.front() != 0;
  auto polyline = [&](std::size_t e) {
    return std::span<const Point2>(d.geometry.data() + d.geometry_first[e], d.geometry_first[e + 1] - d.geometry_first[e]);
  };

  // Every turn at every edge's head. A graph whose edges already encode the turns (a SUMO net, whose
  // graph edges are its connections) gets plain arcs: its U-turns and angles are SUMO's business.
  std::vector<std::uint32_t> base_first(m + 1, 0);
  std::vector<Arc> base;
  std::vector<double> arriving(m), leaving(m);
  for (std::size_t e = 0; e < m; ++e) {
    arriving[e] = arriving_bearing_deg(polyline(e));
    leaving[e] = leaving_bearing_deg(polyline(e));
  }
  for (std::size_t e = 0; e < m; ++e) {
    const auto n = d.edge_head[e].index();
    const EdgeId twin = d.edge_twin[e];
    bool dead_end = true;
    for (auto f = d.first_out[n]; f < d.first_out[n + 1]; ++f) dead_end = dead_end && EdgeId{f} == twin;
    for (auto f = d.first_out[n]; f < d.first_out[n + 1]; ++f) {
      Arc a{f, 0, 0};
      if (!turns_in_edges) {
        a.angle_deg = static_cast<std::int16_t>(std::lround(signed_turn_deg(arriving[e], leaving[f])));
        if (EdgeId{f} == twin) {
          a.bits = static_cast<std::uint16_t>(TurnArc::kTurnUturnBit | (dead_end ? TurnArc::kTurnDeadEndBit : 0));
        }
      }
      base.push_back(a);
    }
    base_first[e + 1] = static_cast<std::uint32_t>(base.size());
  }

  // Restrictions. A via-way restriction (from, via..., to) must know that the vehicle entered the
  // via edges from `from`: the turn from -> via1 leads to a copy of via1, whose turns are via1's
  // except that the one onto via2 leads to a copy of via2, and so on; the last copy carries the ban.
  // Restrictions that share a from edge and a first stretch of via edges share the copies (a trie),
  // so each keeps its meaning.
  std::vector<std::vector<Arc>> copies;
  auto arcs_of = [&](std::uint32_t v) -> std::span<Arc> {
    if (v < m) return {base.data() + base_first[v], base_first[v + 1] - base_first[v]};
    return copies[v - m];
  };
  auto edge_of_vertex = [&](std::uint32_t v) { return v < m ? EdgeId{v} : copy_edge_[v - m]; };
  // An only_* restriction allows, at the end of its path, just its to edge. When one restriction
  // resolves to several paths (a to way that runs both ways from the via node), the allowed set at
  // that vertex is the union of their to edges, so the bans wait until every path is known.
  std::map<std::pair<std::uint32_t, std::uint16_t>, std::vector<EdgeId>> only_allowed;
  const TurnRestrictions& r = d.restrictions;
  for (std::size_t k = 0; k < r.size(); ++k) {
    const std::span<const EdgeId> path(r.edges.data() + r.first[k], r.first[k + 1] - r.first[k]);
    const auto ban = static_cast<std::uint16_t>(r.except_emergency[k] != 0 ? mode_bit(RestrictionMode{r.mode[k]}) << 6
                                                                          : mode_bit(RestrictionMode{r.mode[k]}));
    const bool only = r.only[k] != 0;
    std::uint32_t cur = path[0].v;
    for (std::size_t i = 1; i < path.size(); ++i) {
      const EdgeId next = path[i];
      const bool last = i + 1 == path.size();
      std::size_t pick = arcs_of(cur).size();
      for (std::size_t j = 0; j < arcs_of(cur).size(); ++j) {
        if (edge_of_vertex(arcs_of(cur)[j].other) == next) {
          pick = j;
        } else if (only && !last) {
          arcs_of(cur)[j].bits |= ban;  // along an only_ path's via edges, every way off it is closed
        }
      }
      if (pick == arcs_of(cur).size()) {
        throw MapError("inconsistent road graph: turn restriction " + std::to_string(k) + " names edges that do not meet");
      }
      if (last) {
        if (only) {
          only_allowed[{cur, ban}].push_back(next);
        } else {
          arcs_of(cur)[pick].bits |= ban;
        }
        break;
      }
      if (arcs_of(cur)[pick].other < m) {
        // A copy of the via edge with its own turns, reached only through this turn.
        const auto copy = static_cast<std::uint32_t>(m + copies.size());
        const auto original = arcs_of(next.v);
        copies.emplace_back(original.begin(), original.end());
        copy_edge_.push_back(next);
        arcs_of(cur)[pick].other = copy;
      }
      cur = arcs_of(cur)[pick].other;
    }
  }
  for (const auto& [where, allowed] : only_allowed) {
    for (Arc& a : arcs_of(where.first)) {
      if (std::find(allowed.begin(), allowed.end(), edge_of_vertex(a.other)) == allowed.end()) a.bits |= where.second;
    }
  }

  // Flatten: the edges' arcs, then the copies'; and the same turns by target.
  const std::size_t vertices = m + copies.size();
  first_out_.assign(vertices + 1, 0);
  for (std::uint32_t v = 0; v < vertices; ++v) {
    for (const Arc& a : arcs_of(v)) out_.push_back(a);
    first_out_[v + 1] = static_cast<std::uint32_t>(out_.size());
  }
  first_in_.assign(vertices + 1, 0);
  for (const TurnArc& a : out_) ++first_in_[a.other + 1];
  for (std::size_t v = 0; v < vertices; ++v) first_in_[v + 1] += first_in_[v];
  in_.resize(out_.size());
  std::vector<std::uint32_t> fill(first_in_.begin(), first_in_.end() - 1);
  for (std::uint32_t v = 0; v < vertices; ++v) {
    for (auto i = first_out_[v]; i < first_out_[v + 1]; ++i) in_[fill[out_[i].other]++] = {v, out_[i].angle_deg, out_[i].bits};
  }

  copy_first_.assign(m + 1, 0);
  for (EdgeId e : copy_edge_) ++copy_first_[e.index() + 1];
  for (std::size_t e = 0; e < m; ++e) copy_first_[e + 1] += copy_first_[e];
  copy_vertex_.assign(copy_edge_.size(), 0);
  std::vector<std::uint32_t> at(copy_first_.begin(), copy_first_.end() - 1);
  for (std::uint32_t c = 0; c < copy_edge_.size(); ++c) copy_vertex_[at[copy_edge_[c].index()]++] = static_cast<std::uint32_t>(m + c);
}

}  // namespace corridor::maps
