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

// Forbids turn `a` for the restriction modes `modes`, unless the vehicle belongs to a class in
// `except` (0: no except). Excepted bans on one arc keep the classes they all name.
void add_ban(Arc& a, std::uint8_t modes, std::uint8_t except) {
  if (modes == 0) return;
  if (except == 0) {
    a.bits = static_cast<std::uint16_t>(a.bits | modes);
    return;
  }
  a.except_classes = a.ban_modes_excepted() != 0 ? static_cast<std::uint16_t>(a.except_classes & except) : except;
  a.bits = static_cast<std::uint16_t>(a.bits | (modes << 6));
}

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
  std::vector<double> arriving(turns_in_edges ? 0 : m), leaving(turns_in_edges ? 0 : m);
  for (std::size_t e = 0; e < arriving.size(); ++e) {
    arriving[e] = arriving_bearing_deg(polyline(e));
    leaving[e] = leaving_bearing_deg(polyline(e));
  }
  for (std::size_t e = 0; e < m; ++e) {
    const auto n = d.edge_head[e].index();
    const EdgeId twin = d.edge_twin[e];
    bool dead_end = true;
    for (auto f = d.first_out[n]; f < d.first_out[n + 1]; ++f) dead_end = dead_end && EdgeId{f} == twin;
    for (auto f = d.first_out[n]; f < d.first_out[n + 1]; ++f) {
      Arc a{f, 0, 0, 0};
      if (!turns_in_edges) {
        // A gate inside a way is no turn, whatever the bend (continues_way_at_stop).
        a.angle_deg = continues_way_at_stop(d, EdgeId{static_cast<std::uint32_t>(e)}, EdgeId{f})
                          ? std::int16_t{0}
                          : static_cast<std::int16_t>(std::lround(signed_turn_deg(arriving[e], leaving[f])));
        if (EdgeId{f} == twin) {
          a.bits = static_cast<std::uint16_t>(TurnArc::kTurnUturnBit | (dead_end ? TurnArc::kTurnDeadEndBit : 0));
        }
      }
      base.push_back(a);
    }
    base_first[e + 1] = static_cast<std::uint32_t>(base.size());
  }

  // Restrictions. A via-way restriction (from, via..., to) must know that the vehicle entered the
  // via edges from `from`: the turn from -> via1 leads to a copy of via1 (a state "on via1, having
  // come from `from`"), whose turns are via1's except that the one onto via2 leads to a copy of
  // via2, and so on; the last copy carries the ban. The states form a trie over restriction paths,
  // completed as an Aho-Corasick automaton: a copy also carries every ban, and follows every
  // redirect, of the longest shorter history that is itself a state (at least the plain edge). So
  // restrictions that overlap keep all their meanings, whatever their order in the file.
  std::vector<std::vector<Arc>> copies;
  std::vector<std::vector<EdgeId>> history;  // per copy: the edges driven, the copy's own last
  auto arcs_of = [&](std::uint32_t v) -> std::span<Arc> {
    if (v < m) return {base.data() + base_first[v], base_first[v + 1] - base_first[v]};
    return copies[v - m];
  };
  auto edge_of_vertex = [&](std::uint32_t v) { return v < m ? EdgeId{v} : copy_edge_[v - m]; };
  auto arc_onto = [&](std::uint32_t v, EdgeId next) -> Arc* {
    for (Arc& a : arcs_of(v)) {
      if (edge_of_vertex(a.other) == next) return &a;
    }
    return nullptr;
  };
  // An only_* restriction allows, at each step of its path, just the next edge. When one
  // restriction resolves to several paths (a way that runs both ways from the via node), the allowed
  // set at a state is the union of theirs, so these bans wait until every path is known.
  struct OnlyKey {
    std::uint32_t vertex;
    std::uint8_t modes;
    std::uint8_t except;
    auto operator<=>(const OnlyKey&) const = default;
  };
  std::map<OnlyKey, std::vector<EdgeId>> only_allowed;
  const TurnRestrictions& r = d.restrictions;
  for (std::size_t k = 0; k < r.size(); ++k) {
    const std::span<const EdgeId> path(r.edges.data() + r.first[k], r.first[k + 1] - r.first[k]);
    const std::uint8_t modes = mode_bit(RestrictionMode{r.mode[k]});
    const std::uint8_t except = r.except[k];
    const bool only = r.only[k] != 0;
    std::uint32_t cur = path[0].v;
    for (std::size_t i = 1; i < path.size(); ++i) {
      const EdgeId next = path[i];
      Arc* arc = arc_onto(cur, next);
      if (arc == nullptr) {
        throw MapError("inconsistent road graph: turn restriction " + std::to_string(k) + " names edges that do not meet");
      }
      if (only) only_allowed[{cur, modes, except}].push_back(next);
      if (i + 1 == path.size()) {
        if (!only) add_ban(*arc, modes, except);
        break;
      }
      if (arc->other < m) {
        // A new state: on `next`, having driven the path so far. Its turns are filled in below.
        const auto copy = static_cast<std::uint32_t>(m + copies.size());
        std::vector<EdgeId> driven = cur < m ? std::vector<EdgeId>{EdgeId{cur}} : history[cur - m];
        driven.push_back(next);
        arc->other = copy;
        // The edge's own turns, with plain targets: the redirects its turns may have (trie children
        // of the plain edge's state) are inherited by the failure links below, never followed as
        // this state's own children during insertion.
        const auto original = arcs_of(next.v);
        std::vector<Arc> turns(original.begin(), original.end());
        for (Arc& t : turns) t.other = edge_of_vertex(t.other).v;
        copies.push_back(std::move(turns));
        copy_edge_.push_back(next);
        history.push_back(std::move(driven));
      }
      cur = arc->other;
    }
  }
  for (const auto& [where, allowed] : only_allowed) {
    for (Arc& a : arcs_of(where.vertex)) {
      if (std::find(allowed.begin(), allowed.end(), edge_of_vertex(a.other)) == allowed.end()) add_ban(a, where.modes, where.except);
    }
  }
  // Failure links, shallow states first: a copy inherits the bans and redirects of the longest
  // proper suffix of its history that is a state (the plain edge when no longer one is).
  std::map<std::vector<EdgeId>, std::uint32_t> state_of;
  for (std::size_t c = 0; c < copies.size(); ++c) state_of.emplace(history[c], static_cast<std::uint32_t>(m + c));
  std::vector<std::uint32_t> by_depth(copies.size());
  for (std::size_t c = 0; c < copies.size(); ++c) by_depth[c] = static_cast<std::uint32_t>(c);
  std::stable_sort(by_depth.begin(), by_depth.end(), [&](std::uint32_t x, std::uint32_t y) { return history[x].size() < history[y].size(); });
  for (std::uint32_t c : by_depth) {
    const std::vector<EdgeId>& h = history[c];
    std::uint32_t fallback = h.back().v;
    for (std::size_t skip = 1; skip + 1 < h.size(); ++skip) {
      const auto it = state_of.find(std::vector<EdgeId>(h.begin() + static_cast<std::ptrdiff_t>(skip), h.end()));
      if (it != state_of.end()) {
        fallback = it->second;
        break;
      }
    }
    for (Arc& a : copies[c]) {
      const Arc* f = arc_onto(fallback, edge_of_vertex(a.other));
      if (f == nullptr) continue;
      add_ban(a, f->ban_modes(), 0);
      add_ban(a, f->ban_modes_excepted(), static_cast<std::uint8_t>(f->except_classes));
      if (a.other < m && f->other >= m) a.other = f->other;
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
    for (auto i = first_out_[v]; i < first_out_[v + 1]; ++i) {
      TurnArc a = out_[i];
      a.other = v;
      in_[fill[out_[i].other]++] = a;
    }
  }

  copy_first_.assign(m + 1, 0);
  for (EdgeId e : copy_edge_) ++copy_first_[e.index() + 1];
  for (std::size_t e = 0; e < m; ++e) copy_first_[e + 1] += copy_first_[e];
  copy_vertex_.assign(copy_edge_.size(), 0);
  std::vector<std::uint32_t> at(copy_first_.begin(), copy_first_.end() - 1);
  for (std::uint32_t c = 0; c < copy_edge_.size(); ++c) copy_vertex_[at[copy_edge_[c].index()]++] = static_cast<std::uint32_t>(m + c);
}

}  // namespace corridor::maps
