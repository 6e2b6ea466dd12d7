// D* Lite (Koenig & Likhachev 2002, optimized version with key modifier km): one vehicle's route,
// searched backward from the goal and repaired incrementally as costs change and the vehicle moves.
// One algorithm over two graphs: the turn graph itself (DStarLite, on SearchSpace), and one
// mission's slice of a customizable contraction hierarchy (CchDStarLite, on CchSearchSpace), where
// a metro-scale repair touches a few hundred vertices (the goal's half of the slice) instead of a
// city.
// Optionally, raises (cost increases) are repaired lazily, as in Delayed D* (Ferguson & Stentz
// 2005): only where they reach the vehicle's current path. Measured slower at metro scale (see
// docs/routing.md), so off by default.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

#include "planner/cch_search_space.hpp"
#include "planner/indexed_heap.hpp"
#include "planner/one_to_one_search.hpp"
#include "planner/paged_vertex_state.hpp"
#include "planner/route.hpp"
#include "planner/search_space.hpp"

namespace corridor::planner {

struct ReplanStats {
  std::uint64_t expanded = 0;        // vertices taken off the queue
  std::uint64_t rekeyed = 0;         // of those, put back with a fresher key
  std::uint64_t underconsistent = 0;  // of those, raised to infinity (a cost increase propagating)
  std::uint64_t updated = 0;         // rhs values changed
  std::uint64_t path_checks = 0;     // lazy raises: walks of the path looking for stale values
  std::uint64_t activated = 0;       // lazy raises: stale vertices those walks put on the queue
};

struct DStarLiteOptions {
  // true: a vertex whose value a cost change raised (underconsistent) waits off the queue until a
  // path check finds it on the vehicle's path; from there the raise runs as in the paper. Its stale
  // g is a lower bound, and the final path is checked consistent end to end, so routes stay
  // optimal; raises that never reach the path are never paid for. false: the paper's eager repair,
  // which queues every inconsistent vertex at once. On Porto the stale values that lazy raises leave
  // behind spread through later decreases and must be raised after all: 1.6x the raises, p99 2x.
  bool lazy_raises = false;
};

// Space: SearchSpace (Source = TravelCost) or CchSearchSpace (Source = CchMetric).
template <class Space>
class BasicDStarLite {
 public:
  using Via = typename Space::Via;

  // `source` must outlive the planner. The caller changes the CostOverlay behind it and then reports
  // the changed ids through edges_changed / nodes_changed before the next replan(). On a CCH, the
  // caller first customizes the metric with the same changes and also reports the arcs it changed
  // through arcs_changed.
  BasicDStarLite(const typename Space::Source& source, std::vector<EdgePoint> starts, std::vector<EdgePoint> goals,
                 DStarLiteOptions options = {});

  // The vehicle has moved. Cheap: the repair happens in replan() (on a hierarchy, S's arcs are
  // derived here again: a sweep of the start's half).
  void move_start(std::vector<EdgePoint> starts);
  void edges_changed(std::span<const EdgeId> edges);
  void nodes_changed(std::span<const NodeId> nodes);
  // The metric's customization changed these CCH arcs' weights.
  void arcs_changed(std::span<const std::uint32_t> arcs)
    requires std::is_same_v<Space, CchSearchSpace>;

  // ComputeShortestPath: brings the plan up to date with all reported changes.
  ReplanStats replan();

  // Cost from the vehicle to the goal (kInfCost when unreachable); valid after replan().
  // rhs, not g: S has no predecessors, so the search may stop with S overconsistent.
  [[nodiscard]] double cost_to_goal_s() const { return cut_off_ ? kInfCost : rhs(space_.start()); }
  // The current route, extracted greedily from the g values; valid after replan().
  [[nodiscard]] Route route() const { return space_.route_along(path()); }
  // The arcs that route takes, from S to G; empty when there is none. Before replan(), a greedy
  // walk over the old values: some path, or none, at most max_path_arcs long.
  [[nodiscard]] std::vector<Via> path() const;

  [[nodiscard]] const Space& space() const { return space_; }
  // What this planner holds: its vertex pages, open list and start points. It grows with the part
  // of the graph the searches touched, not with the graph.
  [[nodiscard]] std::size_t memory_bytes() const;

  // Checks D* Lite's invariants over every vertex: rhs(u) = min over successors of c + g, and a
  // vertex is queued exactly when it is inconsistent (lazy raises: every overconsistent vertex is
  // queued, and every queued one is inconsistent). O(V + E); for tests. Empty when all hold.
  [[nodiscard]] std::string invariant_violation() const;

 private:
  struct Key {
    double k1;
    double k2;
    friend bool operator<(const Key& a, const Key& b) { return a.k1 < b.k1 || (a.k1 == b.k1 && a.k2 < b.k2); }
  };

  [[nodiscard]] Key calculate_key(Vertex s) const;
  [[nodiscard]] double min_successor_cost(Vertex u) const;
  // Queues u if inconsistent, else takes it off. Lazy raises: an underconsistent u is queued only
  // if it already was, or `activate` is set.
  void update_vertex(Vertex u, bool activate = false);
  void recompute_rhs(Vertex u);
  // ComputeShortestPath's loop, until the start's key is reached.
  void compute_shortest_path(ReplanStats& stats);
  // Walks the greedy path from the start and queues the first vertex on it whose value
  // is stale (underconsistent). False when the whole path is consistent: it is then optimal.
  bool activate_stale_on_path(ReplanStats& stats);

  [[nodiscard]] double g(Vertex v) const { return states_->get(v.v).g; }
  [[nodiscard]] double rhs(Vertex v) const { return states_->get(v.v).rhs; }

  Space space_;
  DStarLiteOptions options_;
  std::unique_ptr<PagedVertexStates> states_;  // on the heap: the open list points into it
  IndexedHeap<Key, PagedVertexStates::HeapPositions> open_;
  double km_ = 0.0;
  bool cut_off_ = false;  // every arc out of S or into G is closed: no route, repair deferred
};

extern template class BasicDStarLite<SearchSpace>;
extern template class BasicDStarLite<CchSearchSpace>;
using DStarLite = BasicDStarLite<SearchSpace>;
using CchDStarLite = BasicDStarLite<CchSearchSpace>;

}  // namespace corridor::planner
