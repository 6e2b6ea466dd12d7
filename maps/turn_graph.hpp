// The edge-based graph route searches run on: a vertex per directed road edge (the vehicle having
// driven it, at its head), copies of edges that via-way restrictions need to remember where the
// vehicle came from, and an arc per turn from one edge onto the next with its angle, whether it is
// a U-turn, and which restrictions forbid it. Built from the RoadGraph's arrays; profile-free.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "maps/geo.hpp"
#include "maps/ids.hpp"
#include "maps/turn_restriction.hpp"

namespace corridor::maps {

struct RoadGraphData;

// One turn, 8 bytes, stored twice: in its source's out-arcs (`other` = the target vertex) and in its
// target's in-arcs (`other` = the source vertex), so that a search scanning either way reads one
// contiguous run of memory. `bits`: the low 6 bits are the RestrictionMode bits of restrictions
// forbidding the turn with no `except`, the next 6 the same for restrictions whose `except` names
// some vehicle class, then kTurnUturn and kTurnDeadEnd. `except_classes` holds the VehicleClass bits
// those excepted restrictions all name: where two excepted restrictions with different lists forbid
// one turn (never seen in OSM data), it lifts them only for a vehicle both name, which errs towards
// obeying a restriction, never towards breaking one.
struct TurnArc {
  std::uint32_t other;
  // The signed turn, right positive, from the end of one edge to the start of the next; within
  // [-180, 180], so 10 bits hold it and the except mask fits beside it in 8 bytes.
  std::int16_t angle_deg : 10;
  std::uint16_t except_classes : 6;
  std::uint16_t bits;

  [[nodiscard]] std::uint8_t ban_modes() const { return static_cast<std::uint8_t>(bits & 0x3f); }
  [[nodiscard]] std::uint8_t ban_modes_excepted() const { return static_cast<std::uint8_t>((bits >> 6) & 0x3f); }
  [[nodiscard]] bool uturn() const { return (bits & kTurnUturnBit) != 0; }
  [[nodiscard]] bool dead_end() const { return (bits & kTurnDeadEndBit) != 0; }
  // True for the common turn no rule touches: its cost is the angle's alone.
  [[nodiscard]] bool plain() const { return bits == 0; }

  static constexpr std::uint16_t kTurnUturnBit = 1u << 12;    // onto the same road back (the edge's twin)
  static constexpr std::uint16_t kTurnDeadEndBit = 1u << 13;  // that U-turn is at a dead end, the only way on
};
static_assert(sizeof(TurnArc) == 8);

class TurnGraph {
 public:
  TurnGraph() = default;
  // Throws MapError for a restriction whose edges do not follow each other.
  explicit TurnGraph(const RoadGraphData& data);

  // Vertices [0, edge_count) are the edges themselves; copies follow.
  [[nodiscard]] std::size_t vertex_count() const { return first_out_.empty() ? 0 : first_out_.size() - 1; }
  [[nodiscard]] std::size_t copy_count() const { return copy_edge_.size(); }
  [[nodiscard]] std::size_t arc_count() const { return out_.size(); }
  [[nodiscard]] EdgeId edge_of(std::uint32_t v) const {
    return v < edge_count_ ? EdgeId{v} : copy_edge_[v - edge_count_];
  }
  // The copies of edge e (vertices beyond the edges), usually none.
  [[nodiscard]] std::span<const std::uint32_t> copies_of(EdgeId e) const {
    return {copy_vertex_.data() + copy_first_[e.index()], copy_first_[e.index() + 1] - copy_first_[e.index()]};
  }

  // The turns out of v (TurnArc::other = target) and into v (TurnArc::other = source).
  [[nodiscard]] std::span<const TurnArc> arcs_out(std::uint32_t v) const {
    return {out_.data() + first_out_[v], first_out_[v + 1] - first_out_[v]};
  }
  [[nodiscard]] std::span<const TurnArc> arcs_in(std::uint32_t v) const {
    return {in_.data() + first_in_[v], first_in_[v + 1] - first_in_[v]};
  }

 private:
  std::size_t edge_count_ = 0;
  std::vector<std::uint32_t> first_out_;
  std::vector<TurnArc> out_;
  std::vector<std::uint32_t> first_in_;
  std::vector<TurnArc> in_;
  std::vector<EdgeId> copy_edge_;
  std::vector<std::uint32_t> copy_first_;
  std::vector<std::uint32_t> copy_vertex_;
};

// Compass bearings (clockwise from north, degrees) leaving an edge's tail and arriving at its head,
// from the first and last pieces of its polyline longer than a few centimetres.
double leaving_bearing_deg(std::span<const Point2> polyline);
double arriving_bearing_deg(std::span<const Point2> polyline);
// The signed turn (right positive, in (-180, 180]) from one bearing to another.
double signed_turn_deg(double from_bearing_deg, double to_bearing_deg);

}  // namespace corridor::maps
