#include "planner/cch_topology.hpp"

#include <metis.h>

#include <algorithm>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>

namespace corridor::planner {
namespace {

// The turn graph without directions, loops or repeated pairs, as METIS takes it.
struct UndirectedGraph {
  std::vector<idx_t> first;
  std::vector<idx_t> adjacent;
};

UndirectedGraph undirected(const maps::TurnGraph& turns) {
  const std::size_t n = turns.vertex_count();
  std::vector<std::vector<idx_t>> lists(n);
  for (std::uint32_t u = 0; u < n; ++u) {
    for (const maps::TurnArc& a : turns.arcs_out(u)) {
      if (a.other == u) continue;
      lists[u].push_back(static_cast<idx_t>(a.other));
      lists[a.other].push_back(static_cast<idx_t>(u));
    }
  }
  UndirectedGraph g;
  g.first.reserve(n + 1);
  g.first.push_back(0);
  for (auto& l : lists) {
    std::sort(l.begin(), l.end());
    l.erase(std::unique(l.begin(), l.end()), l.end());
    g.adjacent.insert(g.adjacent.end(), l.begin(), l.end());
    g.first.push_back(static_cast<idx_t>(g.adjacent.size()));
  }
  return g;
}

// Nested dissection (METIS_NodeND): separators last, so contracting in this order adds few
// shortcuts and the elimination tree is shallow. iperm[v] is v's rank.
std::vector<std::uint32_t> nested_dissection_ranks(const maps::TurnGraph& turns) {
  const std::size_t n = turns.vertex_count();
  std::vector<std::uint32_t> rank(n);
  UndirectedGraph g = undirected(turns);
  if (g.adjacent.size() > static_cast<std::size_t>(std::numeric_limits<idx_t>::max())) {
    throw std::length_error("turn graph too large for METIS: " + std::to_string(g.adjacent.size()) + " adjacencies");
  }
  // METIS 5.1 bisects without checking for a graph with no edges; any order serves one.
  if (n < 2 || g.adjacent.empty()) {
    std::iota(rank.begin(), rank.end(), 0u);
    return rank;
  }
  idx_t nv = static_cast<idx_t>(n);
  idx_t options[METIS_NOPTIONS];
  METIS_SetDefaultOptions(options);
  options[METIS_OPTION_NUMBERING] = 0;
  options[METIS_OPTION_SEED] = 1;  // the same map always gets the same order
  // The smallest of four separators at each level: on Porto's turn graph 2 % fewer arcs, and
  // partial customization 9 % faster at p50 and 16 % at p99, for 0.7 s more preprocessing.
  options[METIS_OPTION_NSEPS] = 4;
  std::vector<idx_t> perm(n), iperm(n);
  const int status = METIS_NodeND(&nv, g.first.data(), g.adjacent.data(), nullptr, options, perm.data(), iperm.data());
  if (status != METIS_OK) throw std::runtime_error("METIS_NodeND failed with status " + std::to_string(status));
  for (std::size_t v = 0; v < n; ++v) rank[v] = static_cast<std::uint32_t>(iperm[v]);
  return rank;
}

}  // namespace

CchTopology::CchTopology(const maps::TurnGraph& turns) : turns_(&turns) {
  const std::size_t n = turns.vertex_count();
  rank_ = nested_dissection_ranks(turns);
  vertex_at_.resize(n);
  for (std::uint32_t v = 0; v < n; ++v) vertex_at_[rank_[v]] = v;

  // The turn graph's out-arcs, indexed as one array (arcs_out spans are slices of it).
  if (n > 0) turn_arcs_base_ = turns.arcs_out(0).data();
  turn_arc_source_.resize(turns.arc_count());
  for (std::uint32_t u = 0; u < n; ++u) {
    for (const maps::TurnArc& a : turns.arcs_out(u)) turn_arc_source_[turn_arc_index(a)] = u;
  }

  // Contraction by rank: a vertex's higher neighbours become a clique. With the elimination tree
  // it is enough to hand them to the lowest of them (its parent), who passes them on in turn.
  std::vector<std::vector<std::uint32_t>> higher(n);
  for (std::uint32_t u = 0; u < n; ++u) {
    for (const maps::TurnArc& a : turns.arcs_out(u)) {
      if (a.other == u) continue;
      const std::uint32_t ru = rank_[u], rv = rank_[a.other];
      higher[std::min(ru, rv)].push_back(std::max(ru, rv));
    }
  }
  first_up_.assign(n + 1, 0);
  for (std::uint32_t r = 0; r < n; ++r) {
    auto& h = higher[r];
    std::sort(h.begin(), h.end());
    h.erase(std::unique(h.begin(), h.end()), h.end());
    if (h.size() > 1) {
      auto& into = higher[h.front()];
      into.insert(into.end(), h.begin() + 1, h.end());
    }
    // Arc ids, and kNoCchArc beyond them, must fit in 32 bits.
    if (h.size() >= kNoCchArc - first_up_[r]) throw std::length_error("contraction hierarchy too large for 32-bit arc ids");
    first_up_[r + 1] = first_up_[r] + static_cast<std::uint32_t>(h.size());
  }
  up_head_.reserve(first_up_[n]);
  up_tail_.reserve(first_up_[n]);
  for (std::uint32_t r = 0; r < n; ++r) {
    up_head_.insert(up_head_.end(), higher[r].begin(), higher[r].end());
    up_tail_.insert(up_tail_.end(), higher[r].size(), r);
    std::vector<std::uint32_t>().swap(higher[r]);
  }

  // Down lists: every arc again, filed under its head; ascending by tail because arcs are
  // numbered by tail.
  first_down_.assign(n + 1, 0);
  for (std::uint32_t h : up_head_) ++first_down_[h + 1];
  std::partial_sum(first_down_.begin(), first_down_.end(), first_down_.begin());
  down_.resize(up_head_.size());
  std::vector<std::uint32_t> fill(first_down_.begin(), first_down_.end() - 1);
  for (std::uint32_t arc = 0; arc < up_head_.size(); ++arc) down_[fill[up_head_[arc]]++] = {up_tail_[arc], arc};

  input_.assign(up_head_.size(), Input{});
  for (std::uint32_t u = 0; u < n; ++u) {
    for (const maps::TurnArc& a : turns.arcs_out(u)) {
      if (a.other == u) continue;  // a loop never shortens a path
      const std::uint32_t ru = rank_[u], rv = rank_[a.other];
      const std::uint32_t arc = find_arc(ru, rv);
      const std::uint32_t index = turn_arc_index(a);
      // The turn graph has at most one turn from a vertex to another.
      (ru < rv ? input_[arc].up : input_[arc].down) = index;
    }
  }
}

std::uint32_t CchTopology::find_arc(std::uint32_t a, std::uint32_t b) const {
  if (a > b) std::swap(a, b);
  const auto ups = up(a);
  const auto it = std::lower_bound(ups.begin(), ups.end(), b);
  if (it == ups.end() || *it != b) return kNoCchArc;
  return first_up_[a] + static_cast<std::uint32_t>(it - ups.begin());
}

void CchTopology::ancestors(std::span<const std::uint32_t> from, std::vector<std::uint32_t>& out) const {
  out.clear();
  for (std::uint32_t r : from) {
    for (std::uint32_t x = r; x != kNoCchArc; x = parent(x)) out.push_back(x);
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
}

std::size_t CchTopology::memory_bytes() const {
  return (turn_arc_source_.size() + rank_.size() + vertex_at_.size() + first_up_.size() + up_head_.size() +
          up_tail_.size() + first_down_.size()) *
             sizeof(std::uint32_t) +
         down_.size() * sizeof(CchDownArc) + input_.size() * sizeof(Input);
}

}  // namespace corridor::planner
