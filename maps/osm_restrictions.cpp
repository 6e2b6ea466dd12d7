#include "maps/osm_restrictions.hpp"

#include <algorithm>
#include <cmath>

#include "maps/osm_tags.hpp"
#include "maps/turn_graph.hpp"

namespace corridor::maps {
namespace {

std::string_view tag(const osmium::TagList& tags, const char* key) {
  const char* v = tags.get_value_by_key(key);
  return v == nullptr ? std::string_view{} : std::string_view{v};
}

}  // namespace

bool read_restriction(const osmium::Relation& rel, std::vector<OsmRestriction>& restrictions) {
  const auto& t = rel.tags();
  if (tag(t, "type") != "restriction") return true;
  OsmRestriction base;
  for (const auto& m : rel.members()) {
    const std::string_view role = m.role();
    const bool way = m.type() == osmium::item_type::way;
    if (role == "from" && way) base.from_ways.push_back(m.ref());
    if (role == "to" && way) base.to_ways.push_back(m.ref());
    if (role == "via" && way) base.via_ways.push_back(m.ref());
    if (role == "via" && m.type() == osmium::item_type::node) base.via_nodes.push_back(m.ref());
  }
  if (base.from_ways.empty() || base.to_ways.empty() || base.via_nodes.size() + (base.via_ways.empty() ? 0 : 1) != 1) {
    return false;
  }
  base.except = except_classes(tag(t, "except"));
  static constexpr std::pair<const char*, RestrictionMode> kKeys[] = {
      {"restriction", RestrictionMode::all},
      {"restriction:motorcar", RestrictionMode::motorcar},
      {"restriction:motor_vehicle", RestrictionMode::motor_vehicle},
      {"restriction:vehicle", RestrictionMode::vehicle},
      {"restriction:emergency", RestrictionMode::emergency},
      {"restriction:hgv", RestrictionMode::hgv},
  };
  for (const auto& [key, mode] : kKeys) {
    const std::string_view value = tag(t, key);
    const bool no = value.starts_with("no_");
    const bool only = value.starts_with("only_");
    // no_right_turn_on_red and the like forbid a turn against a red light only, which the signal
    // itself governs (and which a preempting vehicle does not meet): no ban on the turn.
    if ((!no && !only) || value.ends_with("_on_red")) continue;
    OsmRestriction r = base;
    r.only = only;
    r.u_turn = value.ends_with("u_turn");
    r.direction = value.ends_with("left_turn")    ? OsmRestriction::Direction::left
                  : value.ends_with("right_turn") ? OsmRestriction::Direction::right
                  : value.ends_with("straight_on") ? OsmRestriction::Direction::straight
                                                   : OsmRestriction::Direction::any;
    r.mode = mode;
    restrictions.push_back(std::move(r));
  }
  return true;
}

RestrictionResolver::RestrictionResolver(const RoadGraph& graph, const std::vector<OsmRestriction>& restrictions)
    : g_(graph) {
  std::vector<osmium::object_id_type> ways, nodes;
  for (const auto& r : restrictions) {
    ways.insert(ways.end(), r.from_ways.begin(), r.from_ways.end());
    ways.insert(ways.end(), r.via_ways.begin(), r.via_ways.end());
    ways.insert(ways.end(), r.to_ways.begin(), r.to_ways.end());
    nodes.insert(nodes.end(), r.via_nodes.begin(), r.via_nodes.end());
  }
  std::sort(ways.begin(), ways.end());
  std::sort(nodes.begin(), nodes.end());
  for (EdgeId e : g_.edges()) {
    if (std::binary_search(ways.begin(), ways.end(), g_.osm_way(e).v)) edges_of_way_[g_.osm_way(e).v].push_back(e);
  }
  // A via node split by a barrier is several graph nodes: each gets the restriction.
  for (NodeId v : g_.nodes()) {
    if (std::binary_search(nodes.begin(), nodes.end(), g_.osm_node(v).v)) nodes_of_osm_[g_.osm_node(v).v].push_back(v);
  }
}

std::size_t RestrictionResolver::resolve(const OsmRestriction& r, TurnRestrictions& out) const {
  std::size_t added = 0;
  for (auto from_way : r.from_ways) {
    for (auto to_way : r.to_ways) {
      if (!r.via_nodes.empty()) {
        const auto it = nodes_of_osm_.find(r.via_nodes.front());
        if (it == nodes_of_osm_.end()) continue;
        for (NodeId via : it->second) {
          for (EdgeId e : g_.in_edges(via)) {
            if (g_.osm_way(e).v != from_way) continue;
            std::vector<EdgeId> to;
            for (EdgeId f : g_.out_edges(via)) {
              if (g_.osm_way(f).v != to_way) continue;
              // From a way onto itself: the U-turn for *_u_turn, otherwise straight on through.
              if (from_way == to_way && (f == g_.twin(e)) != r.u_turn) continue;
              to.push_back(f);
            }
            for (EdgeId f : pick_by_direction(r, e, std::move(to))) {
              out.add({e, f}, r.only, r.mode, r.except);
              ++added;
            }
          }
        }
        continue;
      }
      const auto from = edges_of_way_.find(from_way);
      if (from == edges_of_way_.end()) continue;
      TurnRestrictions paths;
      std::size_t found = 0;
      for (EdgeId e : from->second) {
        std::vector<EdgeId> path{e};
        walk_via(r, to_way, path, paths, found);
      }
      // A from way that reaches the via ways by two edges runs through the junction where they
      // start: the restriction does not say from which side it binds, and banning both can leave a
      // street with no way out. OSRM drops it as ambiguous; so do we (it counts as unresolved).
      std::vector<EdgeId> firsts;
      for (std::size_t k = 0; k < paths.size(); ++k) firsts.push_back(paths.edges[paths.first[k]]);
      std::sort(firsts.begin(), firsts.end());
      if (std::unique(firsts.begin(), firsts.end()) - firsts.begin() > 1) continue;
      for (std::size_t k = 0; k < paths.size(); ++k) {
        out.add(std::vector<EdgeId>(paths.edges.begin() + paths.first[k], paths.edges.begin() + paths.first[k + 1]),
                paths.only[k] != 0, RestrictionMode{paths.mode[k]}, paths.except[k]);
      }
      added += found;
    }
  }
  return added;
}

void RestrictionResolver::walk_via(const OsmRestriction& r, osmium::object_id_type to_way, std::vector<EdgeId>& path,
                                   TurnRestrictions& out, std::size_t& added) const {
  constexpr std::size_t kMaxViaEdges = 32;
  const NodeId at = g_.head(path.back());
  const bool on_via = path.size() > 1;
  if (on_via && covers_via(r, path)) {
    std::vector<EdgeId> to;
    for (EdgeId f : g_.out_edges(at)) {
      if (f != g_.twin(path.back()) && g_.osm_way(f).v == to_way) to.push_back(f);
    }
    for (EdgeId f : pick_by_direction(r, path.back(), std::move(to))) {
      path.push_back(f);
      out.add(path, r.only, r.mode, r.except);
      ++added;
      path.pop_back();
    }
  }
  for (EdgeId f : g_.out_edges(at)) {
    if (f == g_.twin(path.back())) continue;
    const auto way = g_.osm_way(f).v;
    const bool via = std::find(r.via_ways.begin(), r.via_ways.end(), way) != r.via_ways.end();
    if (!via || path.size() > kMaxViaEdges || std::find(path.begin(), path.end(), f) != path.end()) continue;
    path.push_back(f);
    walk_via(r, to_way, path, out, added);
    path.pop_back();
  }
}

std::vector<EdgeId> RestrictionResolver::pick_by_direction(const OsmRestriction& r, EdgeId in,
                                                          std::vector<EdgeId> candidates) const {
  if (candidates.size() < 2 || r.direction == OsmRestriction::Direction::any) return candidates;
  auto turn = [&](EdgeId f) { return signed_turn_deg(arriving_bearing_deg(g_.geometry(in)), leaving_bearing_deg(g_.geometry(f))); };
  // Left: the most negative turn (right positive); right: the most positive; straight: the smallest.
  auto score = [&](EdgeId f) {
    const double t = turn(f);
    return r.direction == OsmRestriction::Direction::left ? t : r.direction == OsmRestriction::Direction::right ? -t : std::abs(t);
  };
  return {*std::min_element(candidates.begin(), candidates.end(), [&](EdgeId a, EdgeId b) { return score(a) < score(b); })};
}

bool RestrictionResolver::covers_via(const OsmRestriction& r, const std::vector<EdgeId>& path) const {
  for (auto w : r.via_ways) {
    if (std::none_of(path.begin() + 1, path.end(), [&](EdgeId e) { return g_.osm_way(e).v == w; })) return false;
  }
  return true;
}

}  // namespace corridor::maps
