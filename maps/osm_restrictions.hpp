// OSM turn-restriction relations: read from a relation's tags and members, and resolved onto the
// edges of a built road graph (maps/turn_restriction.hpp holds the result).
#pragma once

#include <osmium/osm/relation.hpp>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "maps/road_graph.hpp"
#include "maps/turn_restriction.hpp"

namespace corridor::maps {

// A type=restriction relation in OSM terms, one per restriction key it carries.
struct OsmRestriction {
  std::vector<osmium::object_id_type> from_ways;
  std::vector<osmium::object_id_type> via_nodes;  // at most one in valid data
  std::vector<osmium::object_id_type> via_ways;
  std::vector<osmium::object_id_type> to_ways;
  bool only = false;
  bool u_turn = false;  // no_u_turn / only_u_turn: the to edge is the from edge's twin
  // The turn the value names (no_left_turn, only_straight_on, ...). Where the to way leaves the via
  // in more than one direction, it picks the one meant; `any` (no_entry, no_exit) takes them all.
  enum class Direction : std::uint8_t { any, left, right, straight } direction = Direction::any;
  RestrictionMode mode = RestrictionMode::all;
  std::uint8_t except = 0;  // VehicleClass bits its `except` names
};

// Appends one OsmRestriction per restriction key a type=restriction relation carries
// (`restriction`, `restriction:motorcar|motor_vehicle|vehicle|emergency|hgv`, with a no_* or only_*
// value). `restriction:conditional` (time or vehicle conditions) is ignored: an emergency run cannot
// wait for a condition to be evaluated, and OSRM's car profile ignores it too. Returns false for a
// restriction relation without from and to ways and exactly one via (a node, or ways); true
// otherwise, including for relations that are not restrictions.
bool read_restriction(const osmium::Relation& relation, std::vector<OsmRestriction>& out);

// The edge paths an OSM restriction names in the built graph: every from edge arriving at the via
// node (or at the start of the via ways), through the via ways' edges in any order they connect,
// onto every to edge. A via-way restriction whose from way reaches the via ways by more than one
// edge (it runs through their first junction) is ambiguous and resolves to nothing, as in OSRM. A restriction whose members are not in the graph (cut off by the extract,
// one-way the other way, not drivable) resolves to nothing.
class RestrictionResolver {
 public:
  RestrictionResolver(const RoadGraph& graph, const std::vector<OsmRestriction>& restrictions);

  // Appends the restriction's paths; returns how many.
  std::size_t resolve(const OsmRestriction& r, TurnRestrictions& out) const;

 private:
  // Depth-first along the via ways from the head of path.back(), appending every path that reaches
  // a to edge after driving all the via ways.
  void walk_via(const OsmRestriction& r, osmium::object_id_type to_way, std::vector<EdgeId>& path, TurnRestrictions& out,
                std::size_t& added) const;
  // Of the to edges after `in`, the one the restriction's direction names (all of them for `any`).
  [[nodiscard]] std::vector<EdgeId> pick_by_direction(const OsmRestriction& r, EdgeId in, std::vector<EdgeId> candidates) const;
  // Every via way is driven by some edge of path (path[0] is the from edge).
  [[nodiscard]] bool covers_via(const OsmRestriction& r, const std::vector<EdgeId>& path) const;

  const RoadGraph& g_;
  std::unordered_map<osmium::object_id_type, std::vector<EdgeId>> edges_of_way_;
  std::unordered_map<osmium::object_id_type, std::vector<NodeId>> nodes_of_osm_;
};

}  // namespace corridor::maps
