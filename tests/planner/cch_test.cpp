#include <gtest/gtest.h>

#include <algorithm>
#include <iterator>
#include <random>
#include <set>

#include "maps/graph_builder.hpp"
#include "planner/cch_metric.hpp"
#include "planner/cch_topology.hpp"
#include "planner/dstar_lite.hpp"
#include "planner/one_to_one_search.hpp"
#include "planner/settled_replan.hpp"
#include "tests/planner/test_graphs.hpp"

namespace corridor::planner {
namespace {

using testing::random_grid;

// A random grid, its hierarchy, and the metric of the oracle profile at free flow.
struct GridHierarchy {
  GridHierarchy(std::uint64_t seed, std::uint32_t rows, std::uint32_t cols)
      : g(random_grid(seed, rows, cols)), overlay(g), cost(g, overlay, testing::oracle_profile(seed, 25.0)), t(g.turns()),
        metric(t, cost) {}
  maps::RoadGraph g;
  CostOverlay overlay;
  TravelCost cost;
  CchTopology t;
  CchMetric metric;
};

// A batch of congestion: `count` random edges closed, cleared or slowed by ×1–5 with a queue, and
// now and then a node's delay; appended to `edges` and `nodes`.
void random_batch(const maps::RoadGraph& g, CostOverlay& overlay, std::mt19937_64& rng, int count, std::vector<EdgeId>& edges,
                  std::vector<NodeId>& nodes) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int k = 0; k < count; ++k) {
    const EdgeId e = testing::random_point(g, rng).edge;
    const double r = unit(rng);
    if (r < 0.1) {
      overlay.close_edge(e);
    } else if (r < 0.45) {
      overlay.reset_edge(e);
    } else {
      overlay.set_edge(e, {1.0 + unit(rng) * 4.0, unit(rng) < 0.5 ? unit(rng) * 60.0 : 0.0});
    }
    edges.push_back(e);
  }
  if (unit(rng) < 0.3) {
    const NodeId n{std::uniform_int_distribution<std::uint32_t>(0, static_cast<std::uint32_t>(g.node_count() - 1))(rng)};
    overlay.set_node_delay(n, unit(rng) < 0.5 ? 0.0 : unit(rng) * 30.0);
    nodes.push_back(n);
  }
}

// A random batch of `count` changes (random_batch), customized into `metric`: returns the arcs
// whose weights moved; the edges changed are appended to `edges`.
std::vector<std::uint32_t> customize_random_batch(const maps::RoadGraph& g, CostOverlay& overlay, std::mt19937_64& rng, int count,
                                                  CchMetric& metric, std::vector<EdgeId>& edges) {
  std::vector<NodeId> nodes;
  random_batch(g, overlay, rng, count, edges, nodes);
  std::vector<std::uint32_t> changed;
  metric.edges_changed(edges, changed);
  metric.nodes_changed(nodes, changed);
  return changed;
}

// The contraction is a chordal supergraph of the turn graph: every turn has an arc, the higher
// neighbours of a vertex are pairwise joined, and they all lie on its elimination-tree path.
TEST(CchTopology, ContractionIsChordalAndHoldsEveryTurn) {
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    const auto grid = random_grid(seed, 8, 9);
    const auto g = testing::with_random_restrictions(grid, seed, grid.edge_count() / 6);
    const maps::TurnGraph& turns = g.turns();
    const CchTopology t(turns);
    ASSERT_EQ(t.vertex_count(), turns.vertex_count());
    for (std::uint32_t v = 0; v < turns.vertex_count(); ++v) {
      ASSERT_EQ(t.vertex_at(t.rank(v)), v);
      for (const maps::TurnArc& a : turns.arcs_out(v)) {
        if (a.other == v) continue;
        const std::uint32_t arc = t.find_arc(t.rank(v), t.rank(a.other));
        ASSERT_NE(arc, kNoCchArc) << "seed " << seed;
        const auto& in = t.input(arc);
        const std::uint32_t index = t.rank(v) < t.rank(a.other) ? in.up : in.down;
        ASSERT_NE(index, kNoCchArc);
        EXPECT_EQ(&t.turn_arc(index), &a);
        EXPECT_EQ(t.turn_arc_source(index), v);
      }
    }
    std::vector<std::uint32_t> path;
    for (std::uint32_t r = 0; r < t.vertex_count(); ++r) {
      const auto ups = t.up(r);
      ASSERT_TRUE(std::is_sorted(ups.begin(), ups.end()));
      for (std::size_t i = 0; i < ups.size(); ++i) {
        ASSERT_GT(ups[i], r);
        for (std::size_t j = i + 1; j < ups.size(); ++j) ASSERT_NE(t.find_arc(ups[i], ups[j]), kNoCchArc) << "seed " << seed;
      }
      const std::uint32_t one[] = {r};
      t.ancestors(one, path);
      for (std::uint32_t u : ups) EXPECT_TRUE(std::binary_search(path.begin(), path.end(), u)) << "seed " << seed;
      for (const CchDownArc& d : t.down(r)) EXPECT_EQ(t.head(d.arc), r);
    }
  }
}

// Partial customization ends exactly where a full customization of the changed overlay does, arc
// by arc, whatever mix of rises, falls, closures and node delays a batch brings.
TEST(CchMetric, PartialCustomizationEqualsFullCustomization) {
  int batches = 0;
  for (std::uint64_t seed = 1; seed <= 40; ++seed) {
    const auto grid = random_grid(seed, 7, 8);
    // Height limits too: the fire engine (every fourth seed) is kept off those edges for good.
    const auto g = testing::with_random_stops(
        testing::with_random_height_limits(testing::with_random_restrictions(grid, seed, grid.edge_count() / 8), seed, 12), seed, 9);
    CostOverlay overlay(g);
    const TravelCost cost(g, overlay, testing::oracle_profile(seed, 25.0));
    const CchTopology t(g.turns());
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    // Half the metrics are built while some edges are closed, and see them reopen in the first
    // batch: which directions can ever be driven must not be read from the overlay of the day.
    std::vector<EdgeId> closed_at_start;
    for (int k = 0; k < (seed % 2 == 0 ? 6 : 0); ++k) {
      closed_at_start.push_back(testing::random_point(g, rng).edge);
      overlay.close_edge(closed_at_start.back());
    }
    CchMetric metric(t, cost);
    ASSERT_EQ(metric.invariant_violation(), "");
    for (int batch = 0; batch < 30; ++batch) {
      std::vector<EdgeId> edges;
      std::vector<NodeId> nodes;
      if (batch == 0) {
        for (EdgeId e : closed_at_start) overlay.reset_edge(e);
        edges = closed_at_start;
      }
      random_batch(g, overlay, rng, 5, edges, nodes);
      std::vector<std::uint32_t> changed, changed_by_nodes;
      metric.edges_changed(edges, changed);
      metric.nodes_changed(nodes, changed_by_nodes);
      const CchMetric fresh(t, cost);
      std::vector<std::uint32_t> differ;
      for (std::uint32_t arc = 0; arc < t.arc_count(); ++arc) {
        ASSERT_EQ(metric.up_s(arc), fresh.up_s(arc)) << "seed " << seed << " batch " << batch << " arc " << arc;
        ASSERT_EQ(metric.down_s(arc), fresh.down_s(arc)) << "seed " << seed << " batch " << batch << " arc " << arc;
      }
      ASSERT_EQ(metric.invariant_violation(), "") << "seed " << seed << " batch " << batch;
      // One call reports an arc at most once.
      for (auto* list : {&changed, &changed_by_nodes}) {
        std::sort(list->begin(), list->end());
        EXPECT_EQ(std::adjacent_find(list->begin(), list->end()), list->end());
      }
      ++batches;
    }
  }
  EXPECT_EQ(batches, 40 * 30);
}

// With lazy rises, every weight stays at or below the full customization's, and settling an arc
// brings it exactly there, however many batches ago the arc was last settled and whatever changed
// below it since (a settled arc is not looked at again until something in its subtree changes).
TEST(CchMetric, LazyRisesSettleToTheFullCustomization) {
  int settled = 0, raised_total = 0;
  for (std::uint64_t seed = 1; seed <= 30; ++seed) {
    const auto grid = random_grid(seed, 7, 8);
    const auto g = testing::with_random_stops(testing::with_random_restrictions(grid, seed, grid.edge_count() / 8), seed, 9);
    CostOverlay overlay(g);
    const TravelCost cost(g, overlay, testing::oracle_profile(seed, 25.0));
    const CchTopology t(g.turns());
    CchMetric lazy(t, cost, CchMetricOptions{.lazy_rises = true});
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    std::uniform_int_distribution<std::uint32_t> any_arc(0, static_cast<std::uint32_t>(t.arc_count() - 1));
    for (int batch = 0; batch < 30; ++batch) {
      std::vector<EdgeId> edges;
      std::vector<std::uint32_t> changed = customize_random_batch(g, overlay, rng, 4, lazy, edges);
      const CchMetric fresh(t, cost);
      for (std::uint32_t arc = 0; arc < t.arc_count(); ++arc) {
        ASSERT_LE(lazy.up_s(arc), fresh.up_s(arc)) << "seed " << seed << " batch " << batch << " arc " << arc;
        ASSERT_LE(lazy.down_s(arc), fresh.down_s(arc)) << "seed " << seed << " batch " << batch << " arc " << arc;
      }
      ASSERT_EQ(lazy.invariant_violation(), "") << "seed " << seed << " batch " << batch;
      // A few arcs per batch (the last batch: all), each in both directions, twice: the second
      // settle finds it exact and raises nothing.
      const std::uint32_t picks = batch == 29 ? static_cast<std::uint32_t>(t.arc_count()) : 6;
      for (std::uint32_t i = 0; i < picks; ++i) {
        const std::uint32_t arc = batch == 29 ? i : any_arc(rng);
        for (const bool upward : {true, false}) {
          std::vector<std::uint32_t> raised;
          const double w = lazy.settle(arc, upward, raised);
          const double expected = upward ? fresh.up_s(arc) : fresh.down_s(arc);
          ASSERT_EQ(w, expected) << "seed " << seed << " batch " << batch << " arc " << arc;
          ASSERT_EQ(upward ? lazy.up_s(arc) : lazy.down_s(arc), expected);
          raised_total += static_cast<int>(raised.size());
          std::vector<std::uint32_t> again;
          EXPECT_EQ(lazy.settle(arc, upward, again), expected);
          EXPECT_TRUE(again.empty());
          ++settled;
        }
      }
      ASSERT_EQ(lazy.invariant_violation(), "") << "seed " << seed << " batch " << batch;
    }
  }
  EXPECT_GT(settled, 0);
  EXPECT_GT(raised_total, 0);  // the rises did wait for settle()
}

// replan_settled settles the metric the planner searches, and no other.
TEST(CchMetric, ReplanSettledRefusesAPlannerOnAnotherMetric) {
  GridHierarchy h(4, 5, 5);
  CchMetric other(h.t, h.cost, CchMetricOptions{.lazy_rises = true});
  const EdgePoint a{EdgeId{0}, 0.0}, b{EdgeId{static_cast<std::uint32_t>(h.g.edge_count() - 1)}, 0.0};
  CchDStarLite planner(h.metric, {a}, {b});
  EXPECT_THROW((void)replan_settled(other, planner), std::invalid_argument);
  EXPECT_EQ(replan_settled(h.metric, planner).repairs, 1u);  // eager: one repair, nothing to settle
  // A lazy metric serves one planner: a second would never hear of the arcs the first settles.
  CchDStarLite first(other, {a}, {b}), second(other, {a}, {b});
  EXPECT_TRUE(replan_settled(other, first).route.found);
  EXPECT_THROW((void)replan_settled(other, second), std::invalid_argument);
  EXPECT_TRUE(replan_settled(other, first).route.found);
}

// An eager metric is always exact: settle() reads the weight and raises nothing.
TEST(CchMetric, SettleOnAnEagerMetricOnlyReads) {
  GridHierarchy h(3, 6, 6);
  std::vector<std::uint32_t> raised;
  for (std::uint32_t arc = 0; arc < h.t.arc_count(); ++arc) {
    EXPECT_EQ(h.metric.settle(arc, true, raised), h.metric.up_s(arc));
    EXPECT_EQ(h.metric.settle(arc, false, raised), h.metric.down_s(arc));
  }
  EXPECT_TRUE(raised.empty());
}

// A shortcut unpacks into the turns it stands for, and they cost what it weighs.
TEST(CchMetric, ShortcutsUnpackIntoTurnsOfTheirWeight) {
  const GridHierarchy h(5, 9, 9);
  const auto& [g, overlay, cost, t, metric] = h;
  int shortcuts = 0;
  std::vector<std::uint32_t> path;
  for (std::uint32_t arc = 0; arc < t.arc_count(); ++arc) {
    for (const bool upward : {true, false}) {
      const double w = upward ? metric.up_s(arc) : metric.down_s(arc);
      if (w >= kInfCost) continue;
      path.clear();
      metric.unpack(arc, upward, path);
      std::uint32_t from = t.vertex_at(upward ? t.tail(arc) : t.head(arc));
      const std::uint32_t to = t.vertex_at(upward ? t.head(arc) : t.tail(arc));
      ASSERT_FALSE(path.empty());
      EXPECT_EQ(path.back(), to);
      double sum = 0.0;
      for (std::uint32_t v : path) {
        const auto [turn, vertex] = cost.turn_onto(from, g.turns().edge_of(v));
        ASSERT_EQ(vertex, v);
        sum = add_cost(sum, add_cost(turn, cost.transit_s(g.turns().edge_of(v))));
        from = v;
      }
      EXPECT_NEAR(sum, w, 1e-9 * std::max(1.0, w));
      if (path.size() > 1) ++shortcuts;
    }
  }
  EXPECT_GT(shortcuts, 50);
}

// A batch of moved arcs names the mission's vertices whose arcs use them, each once: read where
// the mission's vertices lie when the batch is sorted (as the metric hands it out), arc by arc
// otherwise, and both give exactly the downward half's vertices whose successor arcs include one
// of the batch, and S where an upward path from the start can take one.
TEST(CchSearchSpace, VerticesOnABatchOfArcsAreEachArcsOnce) {
  const GridHierarchy h(7, 12, 12);
  const auto& [g, overlay, cost, t, metric] = h;
  std::mt19937 rng(3);
  int found = 0;
  for (int trial = 0; trial < 50; ++trial) {
    const EdgeId from{static_cast<std::uint32_t>(rng() % g.edge_count())};
    const EdgeId to{static_cast<std::uint32_t>(rng() % g.edge_count())};
    const CchSearchSpace space(metric, {{from, 0.0}}, {{to, g.length_m(to)}});
    std::vector<std::uint32_t> batch;
    for (std::uint32_t arc = 0; arc < t.arc_count(); ++arc) {
      if (rng() % 4 == 0) batch.push_back(arc);
    }
    // The oracle: the vertices of the mission's graph with an arc out over a CCH arc of the batch.
    const std::set<std::uint32_t> in_batch(batch.begin(), batch.end());
    std::vector<Vertex> expected;
    for (std::uint32_t v = 0; v < t.vertex_count(); ++v) {
      bool uses = false;
      space.for_each_successor(Vertex{v}, [&](Vertex, double, const CchVia& via) {
        uses = uses || (via.kind == CchVia::Kind::down && in_batch.count(via.arc) > 0);
      });
      if (uses) expected.push_back(Vertex{v});
    }
    // S, when the batch holds an arc open upward out of an ancestor of the start vertex: one that
    // an upward path from the start can take.
    std::set<std::uint32_t> start_side;
    for (std::uint32_t r = t.rank(space.starts()[0].vertex()); r != kNoCchArc; r = t.parent(r)) start_side.insert(r);
    if (std::any_of(batch.begin(), batch.end(), [&](std::uint32_t arc) { return start_side.count(t.tail(arc)) > 0 && metric.open(arc, true); })) {
      expected.push_back(space.start());
    }
    std::vector<Vertex> sorted_batch, shuffled_batch;
    space.vertices_on_arcs(batch, sorted_batch);
    std::shuffle(batch.begin(), batch.end(), rng);
    space.vertices_on_arcs(batch, shuffled_batch);
    EXPECT_EQ(sorted_batch, expected) << "trial " << trial;
    EXPECT_EQ(shuffled_batch, expected) << "trial " << trial;
    found += static_cast<int>(expected.size());
  }
  EXPECT_GT(found, 500);
}

// S's arcs are the cheapest upward paths from the start points to each meeting vertex: after
// every batch of congestion, change of a start edge and move (one start point, whose cost shifts
// the sweep, or two, which seed it at their own costs), the mission's arcs (kept up to date from
// the lowest vertex whose arcs in moved) are those of a mission built afresh, each is the cost of
// the upward arcs it names, and each is what relaxing every upward arc to a fixpoint gives.
TEST(CchSearchSpace, StartArcsAreTheCheapestUpwardPathsWhileCostsChangeAndTheVehicleMoves) {
  int compared = 0;
  for (std::uint64_t seed = 1; seed <= 16; ++seed) {
    GridHierarchy h(seed, 9, 10);
    auto& [g, overlay, cost, t, metric] = h;
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    const std::size_t points = seed % 2 == 0 ? 2 : 1;
    std::vector<EdgePoint> starts;
    for (std::size_t i = 0; i < points; ++i) starts.push_back(testing::random_point(g, rng));
    const EdgePoint goal = testing::random_point(g, rng);
    CchSearchSpace space(metric, starts, {goal});
    // The mission's S arcs against a fresh one's, and against the oracle.
    const auto check = [&](int step) {
      const CchSearchSpace fresh(metric, starts, {goal});
      std::vector<std::pair<Vertex, double>> kept, built;
      space.for_each_successor(space.start(), [&](Vertex v, double c, const CchVia&) { kept.emplace_back(v, c); });
      fresh.for_each_successor(fresh.start(), [&](Vertex v, double c, const CchVia&) { built.emplace_back(v, c); });
      ASSERT_EQ(kept, built) << "seed " << seed << " step " << step;
      // A half carried over from the last start (build_up) finds a batch's vertices as one built
      // afresh does: a sparse batch, as settling reports, and a dense one, as a city's congestion.
      for (const std::uint32_t every : {40u, 3u}) {
        std::vector<std::uint32_t> batch;
        for (std::uint32_t arc = 0; arc < t.arc_count(); ++arc) {
          if (rng() % every == 0) batch.push_back(arc);
        }
        std::vector<Vertex> kept_on, built_on;
        space.vertices_on_arcs(batch, kept_on);
        fresh.vertices_on_arcs(batch, built_on);
        ASSERT_EQ(kept_on, built_on) << "seed " << seed << " step " << step << " every " << every;
      }
      // The oracle: every upward arc relaxed until nothing moves, from the start vertices.
      std::vector<double> up(t.vertex_count(), kInfCost);
      for (const EdgePoint& s : space.starts()) {
        double& at = up[t.rank(s.vertex())];
        at = std::min(at, cost.partial_time_s(s.edge, s.offset_m, g.length_m(s.edge)));
      }
      for (bool moved = true; moved;) {
        moved = false;
        for (std::uint32_t arc = 0; arc < t.arc_count(); ++arc) {
          if (!metric.open(arc, true)) continue;
          const double c = add_cost(up[t.tail(arc)], metric.up_s(arc));
          if (c < up[t.head(arc)] * (1.0 - 1e-12)) {
            up[t.head(arc)] = c;
            moved = true;
          }
        }
      }
      space.for_each_successor(space.start(), [&](Vertex v, double c, const CchVia& via) {
        if (via.kind != CchVia::Kind::start) return;
        EXPECT_NEAR(c, up[v.v], 1e-9 * std::max(1.0, c)) << "seed " << seed << " step " << step;
        // The arcs it names climb from a start vertex to v, and cost c with the start edge's rest.
        double along = 0.0;
        std::set<std::uint32_t> tails, heads;
        space.for_each_hierarchy_arc(via, [&](std::uint32_t arc, bool upward) {
          EXPECT_TRUE(upward);
          tails.insert(t.tail(arc));
          heads.insert(t.head(arc));
          along = add_cost(along, metric.up_s(arc));
        });
        std::vector<std::uint32_t> bottom, top;
        std::set_difference(tails.begin(), tails.end(), heads.begin(), heads.end(), std::back_inserter(bottom));
        std::set_difference(heads.begin(), heads.end(), tails.begin(), tails.end(), std::back_inserter(top));
        const std::uint32_t from = bottom.empty() ? v.v : bottom.front();
        EXPECT_TRUE(top.empty() ? from == v.v : top == std::vector<std::uint32_t>{v.v});
        double rest = kInfCost;
        for (const EdgePoint& s : space.starts()) {
          if (t.rank(s.vertex()) == from) rest = std::min(rest, cost.partial_time_s(s.edge, s.offset_m, g.length_m(s.edge)));
        }
        EXPECT_NEAR(add_cost(rest, along), c, 1e-9 * std::max(1.0, c)) << "seed " << seed << " step " << step;
        ++compared;
      });
    };
    std::vector<Vertex> touched;
    for (int step = 0; step < 40; ++step) {
      std::vector<EdgeId> edges;
      std::vector<std::uint32_t> changed = customize_random_batch(g, overlay, rng, 4, metric, edges);
      space.arcs_changed(changed, touched);
      // A start edge in the batch: D* Lite's edges_changed re-derives S from the start edges.
      if (std::any_of(starts.begin(), starts.end(),
                      [&](const EdgePoint& s) { return std::find(edges.begin(), edges.end(), s.edge) != edges.end(); })) {
        space.refresh_start();
      }
      check(step);
      if (step % 5 == 0) {
        // A start edge's conditions change: only its rest changes, and no arc of the hierarchy.
        overlay.set_edge(starts[0].edge, {1.0 + unit(rng) * 3.0, 0.0});
        changed.clear();
        metric.edges_changed(std::vector<EdgeId>{starts[0].edge}, changed);
        space.arcs_changed(changed, touched);
        space.refresh_start();
        check(step);
      }
      // Along the same edges most of the time, or on to the next edge (a start vertex of the same
      // ancestors but the lowest few), now and then somewhere else.
      for (EdgePoint& s : starts) {
        const double draw = unit(rng);
        const auto next = g.out_edges(g.head(s.edge));
        if (draw < 0.5) {
          s = EdgePoint{s.edge, std::min(g.length_m(s.edge), s.offset_m + unit(rng) * 20.0)};
        } else if (draw < 0.8 && !next.empty()) {
          s = EdgePoint{EdgeId{static_cast<std::uint32_t>((*next.begin()).index() + rng() % next.size())}, 0.0};
        } else {
          s = testing::random_point(g, rng);
        }
      }
      space.move_starts(starts);
      check(step);
    }
  }
  EXPECT_GT(compared, 4000);
}

// The smallest map: one two-way street, two turn-graph vertices joined by the dead-end U-turns.
// The order, the metric and the routes along it (either way, one through a U-turn) still agree
// with Dijkstra.
TEST(CchTopology, OneStreetMap) {
  maps::GraphBuildInput in;
  in.origin = {47.0, 9.5};
  in.node_pos = {{0, 0}, {100, 0}};
  in.node_osm = {OsmNodeId{1}, OsmNodeId{2}};
  in.node_signalized = {0, 0};
  maps::RoadSegment s;
  s.from = 0;
  s.to = 1;
  s.first_point = 0;
  in.points = {in.node_pos[0], in.node_pos[1]};
  s.last_point = 1;
  s.forward_speed_mps = s.backward_speed_mps = 10.0f;
  s.way = OsmWayId{1};
  in.segments.push_back(s);
  const maps::RoadGraph g = maps::build_road_graph(in);
  ASSERT_EQ(g.edge_count(), 2u);
  const CchTopology t(g.turns());
  EXPECT_EQ(t.vertex_count(), g.turns().vertex_count());
  CostOverlay overlay(g);
  const TravelCost cost(g, overlay, testing::free_turns(30.0));
  const CchMetric metric(t, cost);
  EXPECT_EQ(metric.invariant_violation(), "");
  OneToOneSearch dijkstra;
  for (const auto& [from, to] : {std::pair{10.0, 60.0}, std::pair{60.0, 10.0}}) {
    const std::vector<EdgePoint> starts{{EdgeId{0}, from}}, goals{{EdgeId{0}, to}};
    CchDStarLite dstar(metric, starts, goals);
    dstar.replan();
    const Route oracle = dijkstra.run(SearchSpace(cost, starts, goals), false);
    EXPECT_EQ(dstar.cost_to_goal_s(), oracle.travel_time_s) << from << " -> " << to;
    EXPECT_EQ(dstar.route().edges, oracle.edges) << from << " -> " << to;
  }
}

// A metric over another map's hierarchy is refused, not computed with the wrong turns.
TEST(CchMetric, RefusesAHierarchyOfAnotherGraph) {
  const auto a = random_grid(1, 4, 4);
  const auto b = random_grid(2, 4, 4);
  CostOverlay overlay(b);
  const TravelCost cost(b, overlay, {30.0});
  const CchTopology t(a.turns());
  EXPECT_THROW(CchMetric(t, cost), std::invalid_argument);
}

}  // namespace
}  // namespace corridor::planner
