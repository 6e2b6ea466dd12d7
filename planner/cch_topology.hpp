// The metric-independent half of a customizable contraction hierarchy (CCH; Dibbelt, Strasser &
// Wagner 2016) over the turn graph (maps/turn_graph.hpp): a nested-dissection order of its
// vertices (METIS), the chordal supergraph that contracting them in that order produces (its
// upward arcs), and the elimination tree. Built once per map and shared by every metric
// (planner/cch_metric.hpp) and every mission's search (planner/cch_search_space.hpp).
//
// Vertices here are ranks: rank 0 is contracted first, the top separator last. An arc joins a
// lower rank x to a higher rank y and carries two weights in the metric, x→y and y→x.
#pragma once

#include <cstdint>
#include <limits>
#include <span>
#include <utility>
#include <vector>

#include "maps/turn_graph.hpp"

namespace corridor::planner {

inline constexpr std::uint32_t kNoCchArc = std::numeric_limits<std::uint32_t>::max();

// A neighbour of a vertex and the arc joining them. In the topology's down lists the neighbour is
// the arc's lower end (its tail); the metric's open lists reuse it for higher neighbours too.
struct CchDownArc {
  std::uint32_t tail;  // the neighbour: the lower rank, in down lists
  std::uint32_t arc;   // the arc's id
};

class CchTopology {
 public:
  // An arc's input: the turn-graph arc it stands for in each direction (an index into the turn
  // graph's out-arc array), or kNoCchArc where it is a shortcut only.
  struct Input {
    std::uint32_t up = kNoCchArc;    // lower → higher
    std::uint32_t down = kNoCchArc;  // higher → lower
  };

  explicit CchTopology(const maps::TurnGraph& turns);

  [[nodiscard]] std::size_t vertex_count() const { return vertex_at_.size(); }
  [[nodiscard]] std::size_t arc_count() const { return up_head_.size(); }
  [[nodiscard]] std::uint32_t rank(std::uint32_t turn_vertex) const { return rank_[turn_vertex]; }
  [[nodiscard]] std::uint32_t vertex_at(std::uint32_t r) const { return vertex_at_[r]; }

  // The higher ranks r is joined to, ascending; arc ids first_up(r), first_up(r) + 1, ...
  [[nodiscard]] std::span<const std::uint32_t> up(std::uint32_t r) const {
    return {up_head_.data() + first_up_[r], first_up_[r + 1] - first_up_[r]};
  }
  [[nodiscard]] std::uint32_t first_up(std::uint32_t r) const { return first_up_[r]; }
  // The lower ranks r is joined to, ascending, with the arcs' ids.
  [[nodiscard]] std::span<const CchDownArc> down(std::uint32_t r) const {
    return {down_.data() + first_down_[r], first_down_[r + 1] - first_down_[r]};
  }
  // The tail (lower rank) of an arc.
  [[nodiscard]] std::uint32_t tail(std::uint32_t arc) const { return up_tail_[arc]; }
  [[nodiscard]] std::uint32_t head(std::uint32_t arc) const { return up_head_[arc]; }
  // The arc joining ranks a and b (either order), or kNoCchArc.
  [[nodiscard]] std::uint32_t find_arc(std::uint32_t a, std::uint32_t b) const;
  // The elimination tree: the lowest higher neighbour, or kNoCchArc at a root. Every higher
  // neighbour of r is an ancestor of r in this tree (the supergraph is chordal).
  [[nodiscard]] std::uint32_t parent(std::uint32_t r) const {
    return first_up_[r] == first_up_[r + 1] ? kNoCchArc : up_head_[first_up_[r]];
  }
  [[nodiscard]] const Input& input(std::uint32_t arc) const { return input_[arc]; }
  [[nodiscard]] const maps::TurnGraph& turns() const { return *turns_; }
  // The turn graph's out-arc with this index, and its source vertex.
  [[nodiscard]] const maps::TurnArc& turn_arc(std::uint32_t index) const { return turn_arcs_base_[index]; }
  // The index of an arc of turns().arcs_out(...) (a reference into that array).
  [[nodiscard]] std::uint32_t turn_arc_index(const maps::TurnArc& out_arc) const {
    return static_cast<std::uint32_t>(&out_arc - turn_arcs_base_);
  }
  [[nodiscard]] std::uint32_t turn_arc_source(std::uint32_t index) const { return turn_arc_source_[index]; }

  // Ranks from each of `from` up to the root, merged, ascending: the vertices an upward search
  // from them reaches.
  void ancestors(std::span<const std::uint32_t> from, std::vector<std::uint32_t>& out) const;

  [[nodiscard]] std::size_t memory_bytes() const;

 private:
  const maps::TurnGraph* turns_;
  const maps::TurnArc* turn_arcs_base_ = nullptr;
  std::vector<std::uint32_t> turn_arc_source_;
  std::vector<std::uint32_t> rank_;
  std::vector<std::uint32_t> vertex_at_;
  std::vector<std::uint32_t> first_up_;
  std::vector<std::uint32_t> up_head_;
  std::vector<std::uint32_t> up_tail_;
  std::vector<std::uint32_t> first_down_;
  std::vector<CchDownArc> down_;
  std::vector<Input> input_;
};

}  // namespace corridor::planner
