#include "planner/dstar_lite.hpp"

#include <gtest/gtest.h>

#include <optional>
#include <random>
#include <tuple>

#include "planner/cch_metric.hpp"
#include "planner/cch_topology.hpp"
#include "planner/one_to_one_search.hpp"
#include "planner/settled_replan.hpp"
#include "maps/osm_import.hpp"
#include "maps/synthetic_grid.hpp"
#include "tests/planner/test_graphs.hpp"
#include "tests/planner/test_graphs_line.hpp"

namespace corridor::planner {
namespace {

using testing::random_grid;
using testing::random_point;
using testing::with_twin;

void expect_same_cost(double expected, double actual, const std::string& where) {
  if (expected >= kInfCost || actual >= kInfCost) {
    EXPECT_EQ(expected, actual) << where;
  } else {
    EXPECT_NEAR(expected, actual, 1e-9 * std::max(1.0, expected)) << where;
  }
}

// Checks D* Lite's cost, and the cost of the route it extracts, against Dijkstra from scratch.
template <class Planner>
void expect_matches_dijkstra(const Planner& dstar, const TravelCost& cost, const std::vector<EdgePoint>& starts,
                             const std::vector<EdgePoint>& goals, const std::string& where) {
  OneToOneSearch dijkstra;
  const Route oracle = dijkstra.run(SearchSpace(cost, starts, goals), false);
  expect_same_cost(oracle.travel_time_s, dstar.cost_to_goal_s(), where + " (cost_to_goal)");
  const Route r = dstar.route();
  EXPECT_EQ(oracle.found, r.found) << where;
  if (r.found) {
    expect_same_cost(oracle.travel_time_s, r.travel_time_s, where + " (route)");
    // The route must be a connected walk from a start point to a goal point.
    for (std::size_t i = 1; i < r.edges.size(); ++i) {
      ASSERT_EQ(cost.graph().head(r.edges[i - 1]), cost.graph().tail(r.edges[i])) << where;
    }
  }
}

// On edge-based graphs with random turn restrictions (via node and via way) and gates, under
// profiles that differ in what binds them and in their turn and U-turn costs.
TEST(DStarLite, InitialPlanMatchesDijkstraOnRandomGraphs) {
  for (std::uint64_t seed = 1; seed <= 60; ++seed) {
    const auto grid = random_grid(seed, 8, 9);
    const auto g = testing::with_random_stops(testing::with_random_restrictions(grid, seed, grid.edge_count() / 6), seed, 10);
    CostOverlay overlay(g);
    overlay.set_signal_delay(g, 7.5);
    const TravelCost cost(g, overlay, testing::oracle_profile(seed, 30.0));
    const CchTopology topology(g.turns());
    const CchMetric metric(topology, cost);
    std::mt19937_64 rng(seed);
    for (int q = 0; q < 10; ++q) {
      const auto starts = with_twin(g, random_point(g, rng));
      const auto goals = with_twin(g, random_point(g, rng));
      DStarLite dstar(cost, starts, goals);
      dstar.replan();
      expect_matches_dijkstra(dstar, cost, starts, goals, "seed " + std::to_string(seed));
      CchDStarLite on_cch(metric, starts, goals);
      on_cch.replan();
      expect_matches_dijkstra(on_cch, cost, starts, goals, "CCH, seed " + std::to_string(seed));
    }
  }
}

// Thousands of random update sequences: cost increases and decreases on and off the route,
// closures and reopenings, node and movement delay changes, and start moves, checked after every
// replan. On the turn graph (eager and lazy raises), and on a contraction hierarchy, whose metric
// is customized with each batch and checked against its own invariants; on a metric with lazy
// rises too, where the replan settles the arcs its routes take (replan_settled).
enum class Variant { eager, lazy, cch, cch_lazy, cch_settled, cch_settled_lazy };

// One D* Lite of either kind, fed the same reports.
class AnyDStarLite {
 public:
  AnyDStarLite(Variant v, const TravelCost& cost, std::vector<EdgePoint> starts, std::vector<EdgePoint> goals) {
    if (v == Variant::cch || v == Variant::cch_lazy || v == Variant::cch_settled || v == Variant::cch_settled_lazy) {
      topology_.emplace(cost.graph().turns());
      metric_.emplace(*topology_, cost, CchMetricOptions{v == Variant::cch_settled || v == Variant::cch_settled_lazy});
      cch_.emplace(*metric_, std::move(starts), std::move(goals),
                   DStarLiteOptions{v == Variant::cch_lazy || v == Variant::cch_settled_lazy});
    } else {
      flat_.emplace(cost, std::move(starts), std::move(goals), DStarLiteOptions{v == Variant::lazy});
    }
  }
  void move_start(std::vector<EdgePoint> starts) { cch_ ? cch_->move_start(std::move(starts)) : flat_->move_start(std::move(starts)); }
  void changed(const std::vector<EdgeId>& edges, const std::vector<NodeId>& nodes) {
    if (!cch_) {
      flat_->edges_changed(edges);
      flat_->nodes_changed(nodes);
      return;
    }
    std::vector<std::uint32_t> arcs;
    metric_->edges_changed(edges, arcs);
    metric_->nodes_changed(nodes, arcs);
    cch_->edges_changed(edges);
    cch_->nodes_changed(nodes);
    cch_->arcs_changed(arcs);
  }
  ReplanStats replan() {
    if (!cch_) return flat_->replan();
    if (!metric_->lazy_rises()) return cch_->replan();
    SettledReplan r = replan_settled(*metric_, *cch_);
    settled_route_ = std::move(r.route);
    return r.stats;
  }
  // On a lazy metric, the route replan_settled handed back (what its callers use).
  [[nodiscard]] Route route() const {
    if (settled_route_) return *settled_route_;
    return cch_ ? cch_->route() : flat_->route();
  }
  [[nodiscard]] double cost_to_goal_s() const { return cch_ ? cch_->cost_to_goal_s() : flat_->cost_to_goal_s(); }
  [[nodiscard]] std::string invariant_violation() const {
    if (!cch_) return flat_->invariant_violation();
    const std::string metric = metric_->invariant_violation();
    return metric.empty() ? cch_->invariant_violation() : "metric: " + metric;
  }

 private:
  std::optional<DStarLite> flat_;
  std::optional<CchTopology> topology_;
  std::optional<CchMetric> metric_;
  std::optional<CchDStarLite> cch_;
  std::optional<Route> settled_route_;
};

class DStarLiteRepair : public ::testing::TestWithParam<Variant> {};

TEST_P(DStarLiteRepair, ReplanMatchesDijkstraAfterRandomUpdateSequences) {
  int replans = 0;
  constexpr std::uint64_t kSequences = 200;
  for (std::uint64_t seed = 1; seed <= kSequences; ++seed) {
    const auto grid = random_grid(seed, 7, 7 + seed % 4);
    const auto g = testing::with_random_restrictions(grid, seed, grid.edge_count() / 8);
    CostOverlay overlay(g);
    const TravelCost cost(g, overlay, testing::oracle_profile(seed, 25.0));
    std::mt19937_64 rng(seed * 7919);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    auto starts = with_twin(g, random_point(g, rng));
    const auto goals = std::vector<EdgePoint>{random_point(g, rng)};
    AnyDStarLite dstar(GetParam(), cost, starts, goals);
    dstar.replan();
    for (int step = 0; step < 25; ++step) {
      const Route current = dstar.route();
      std::vector<EdgeId> edges;
      std::vector<NodeId> nodes;
      const int updates = std::uniform_int_distribution<int>(1, 6)(rng);
      for (int k = 0; k < updates; ++k) {
        EdgeId e = random_point(g, rng).edge;
        if (unit(rng) < 0.5 && !current.edges.empty()) {
          e = current.edges[std::uniform_int_distribution<std::size_t>(0, current.edges.size() - 1)(rng)];
        }
        const double r = unit(rng);
        if (r < 0.1) {
          overlay.close_edge(e);
        } else if (r < 0.4) {
          overlay.reset_edge(e);
        } else if (r < 0.6) {
          overlay.set_edge(e, {0.5 + unit(rng) * 0.5, 0.0});  // faster than free flow: clamped at vmax
        } else {
          overlay.set_edge(e, {1.0 + unit(rng) * 5.0, unit(rng) < 0.5 ? unit(rng) * 60.0 : 0.0});
        }
        edges.push_back(e);
        if (unit(rng) < 0.3) {
          const NodeId n{std::uniform_int_distribution<std::uint32_t>(0, static_cast<std::uint32_t>(g.node_count() - 1))(rng)};
          overlay.set_node_delay(n, unit(rng) < 0.5 ? 0.0 : unit(rng) * 40.0);
          // And a movement's own delay (a signal's green share): reported through its node.
          const auto ins = g.in_edges(n);
          const auto outs = g.out_edges(n);
          if (!ins.empty() && !outs.empty()) {
            const EdgeId in = ins[std::uniform_int_distribution<std::size_t>(0, ins.size() - 1)(rng)];
            const EdgeId out{(*outs.begin()).v + std::uniform_int_distribution<std::uint32_t>(
                                                      0, static_cast<std::uint32_t>(outs.size() - 1))(rng)};
            overlay.set_turn_delay(in, out, unit(rng) < 0.3 ? 0.0 : unit(rng) * 60.0);
          }
          nodes.push_back(n);
        }
      }
      if (unit(rng) < 0.5) {
        // Move along the current route, or jump somewhere else (a vehicle that left the plan).
        if (current.found && current.edges.size() > 1 && unit(rng) < 0.7) {
          const EdgeId e = current.edges[std::uniform_int_distribution<std::size_t>(1, current.edges.size() - 1)(rng)];
          starts = {EdgePoint{e, g.length_m(e) * unit(rng)}};
        } else {
          starts = with_twin(g, random_point(g, rng));
        }
        dstar.move_start(starts);
      }
      dstar.changed(edges, nodes);
      ASSERT_EQ(dstar.invariant_violation(), "") << "before replan, seed " << seed << " step " << step;
      dstar.replan();
      ASSERT_EQ(dstar.invariant_violation(), "") << "seed " << seed << " step " << step;
      expect_matches_dijkstra(dstar, cost, starts, goals, "seed " + std::to_string(seed) + " step " + std::to_string(step));
      ++replans;
      if (::testing::Test::HasFailure()) return;
    }
  }
  EXPECT_EQ(replans, kSequences * 25);
}

INSTANTIATE_TEST_SUITE_P(EagerLazyAndCch, DStarLiteRepair,
                         ::testing::Values(Variant::eager, Variant::lazy, Variant::cch, Variant::cch_lazy,
                                           Variant::cch_settled, Variant::cch_settled_lazy),
                         [](const ::testing::TestParamInfo<Variant>& p) {
                           switch (p.param) {
                             case Variant::lazy: return "lazy";
                             case Variant::cch: return "cch";
                             case Variant::cch_lazy: return "cch_lazy";
                             case Variant::cch_settled: return "cch_settled";
                             case Variant::cch_settled_lazy: return "cch_settled_lazy";
                             default: return "eager";
                           }
                         });

// A mission that touches a small part of a big graph holds a small part of its state: the per-vertex
// records live in pages allocated on first write.
TEST(DStarLite, MemoryGrowsWithTheSearchNotWithTheGraph) {
  maps::GridSpec spec;
  spec.rows = 200;
  spec.cols = 200;
  spec.seed = 5;
  const auto g = maps::make_perturbed_grid(spec);
  const CostOverlay overlay(g);
  const TravelCost cost(g, overlay, {30.0});
  // Two consecutive edges: a trip of one junction.
  const EdgeId first{static_cast<std::uint32_t>(g.edge_count() / 2)};
  ASSERT_FALSE(g.out_edges(g.head(first)).empty());  // the largest strongly connected part: never a sink
  const EdgeId second = *g.out_edges(g.head(first)).begin();
  DStarLite dstar(cost, {{first, 0.0}}, {{second, g.length_m(second)}});
  dstar.replan();
  ASSERT_TRUE(dstar.route().found);
  const double dense = static_cast<double>(g.turns().vertex_count() * sizeof(VertexState));
  EXPECT_LT(static_cast<double>(dstar.memory_bytes()), 0.05 * dense) << dstar.memory_bytes() << " bytes";
  // The far end of the city costs its pages once it is searched.
  DStarLite across(cost, {{EdgeId{0}, 0.0}}, {{EdgeId{static_cast<std::uint32_t>(g.edge_count() - 1)}, 0.0}});
  across.replan();
  EXPECT_GT(across.memory_bytes(), dstar.memory_bytes());
}

TEST(DStarLite, ReplanMatchesDijkstraAfterCongestionUpdate) {
  const auto g = testing::diamond();
  CostOverlay overlay(g);
  const TravelCost cost(g, overlay, {30.0});
  const EdgeId ab = testing::edge_from_to(g, 1, 2), ad = testing::edge_from_to(g, 1, 4);
  const EdgeId bc = testing::edge_from_to(g, 2, 3), dc = testing::edge_from_to(g, 4, 3);
  const std::vector<EdgePoint> starts{{ab, 0.0}, {ad, 0.0}};
  const std::vector<EdgePoint> goals{{bc, 100.0}, {dc, g.length_m(dc)}};
  DStarLite dstar(cost, starts, goals);
  dstar.replan();
  EXPECT_EQ(dstar.route().edges, (std::vector<EdgeId>{ad, dc}));
  // A queue on D->C makes the straight road faster: the plan switches.
  overlay.set_edge(dc, {1.0, 30.0});
  const std::vector<EdgeId> changed{dc};
  dstar.edges_changed(changed);
  dstar.replan();
  EXPECT_EQ(dstar.route().edges, (std::vector<EdgeId>{ab, bc}));
  EXPECT_DOUBLE_EQ(dstar.cost_to_goal_s(), 20.0);
  expect_matches_dijkstra(dstar, cost, starts, goals, "after increase");
  // The queue clears: back to the detour (a cost decrease).
  overlay.reset_edge(dc);
  dstar.edges_changed(changed);
  dstar.replan();
  EXPECT_EQ(dstar.route().edges, (std::vector<EdgeId>{ad, dc}));
  expect_matches_dijkstra(dstar, cost, starts, goals, "after decrease");
}

TEST(DStarLite, NodeDelayChangeRaisesTheCostThroughTheNode) {
  const auto g = testing::diamond();
  CostOverlay overlay(g);
  const TravelCost cost(g, overlay, {30.0});
  const EdgeId ab = testing::edge_from_to(g, 1, 2), bc = testing::edge_from_to(g, 2, 3);
  // Start at B heading for C: straight on is 10 s. A 100 s signal delay at B is unavoidable, since
  // every way out of B crosses B; the plan keeps the straight road and its cost rises by 100 s.
  const std::vector<EdgePoint> starts{{ab, 100.0}};
  const std::vector<EdgePoint> goals{{bc, 100.0}};
  DStarLite dstar(cost, starts, goals);
  dstar.replan();
  EXPECT_DOUBLE_EQ(dstar.cost_to_goal_s(), 10.0);
  const NodeId b = g.head(ab);
  overlay.set_node_delay(b, 100.0);
  const std::vector<NodeId> changed{b};
  dstar.nodes_changed(changed);
  dstar.replan();
  EXPECT_DOUBLE_EQ(dstar.cost_to_goal_s(), 110.0);
  expect_matches_dijkstra(dstar, cost, starts, goals, "after node delay");
}

TEST(DStarLite, MovingAlongTheRouteKeepsTheRestOfIt) {
  const auto g = random_grid(77, 15, 15);
  CostOverlay overlay(g);
  const TravelCost cost(g, overlay, {30.0});
  std::mt19937_64 rng(77);
  const std::vector<EdgePoint> goals{random_point(g, rng)};
  DStarLite dstar(cost, {random_point(g, rng)}, goals);
  dstar.replan();
  Route r = dstar.route();
  ASSERT_TRUE(r.found);
  while (r.edges.size() > 2) {
    const EdgeId next = r.edges[1];
    const std::vector<EdgeId> rest(r.edges.begin() + 1, r.edges.end());
    dstar.move_start({{next, 0.0}});
    dstar.replan();
    r = dstar.route();
    EXPECT_EQ(r.edges, rest);
  }
}

TEST(DStarLite, UnreachableGoalAndRecovery) {
  const auto g = testing::diamond();
  CostOverlay overlay(g);
  const TravelCost cost(g, overlay, testing::free_turns(30.0));
  const EdgeId ba = testing::edge_from_to(g, 2, 1), bc = testing::edge_from_to(g, 2, 3);
  const std::vector<EdgeId> closed{testing::edge_from_to(g, 1, 2), testing::edge_from_to(g, 1, 4)};
  for (EdgeId e : closed) overlay.close_edge(e);
  DStarLite dstar(cost, {{ba, 0.0}}, {{bc, 50.0}});
  dstar.replan();
  EXPECT_EQ(dstar.cost_to_goal_s(), kInfCost);
  EXPECT_FALSE(dstar.route().found);
  overlay.reset_edge(closed[1]);
  dstar.edges_changed(closed);
  dstar.replan();
  EXPECT_TRUE(dstar.route().found);
  expect_matches_dijkstra(dstar, cost, {{ba, 0.0}}, {{bc, 50.0}}, "reopened");
}

// The same randomized oracle on real maps: trips with congestion on and off the route, start moves
// along the route, and checks after every replan.
class DStarLiteOnExtract : public ::testing::TestWithParam<std::tuple<const char*, Variant>> {};

TEST_P(DStarLiteOnExtract, ReplanMatchesDijkstraWhileDriving) {
  const char* map = std::get<0>(GetParam());
  const auto file = std::filesystem::path(CORRIDOR_SHARED_DATA_DIR) / "osm" / map;
  if (!std::filesystem::exists(file)) GTEST_SKIP() << "shared data not present: " << file;
  maps::OsmImportOptions options;
  options.show_progress = false;
  const maps::RoadGraph g = maps::import_osm(file, options);
  std::mt19937_64 rng(2024);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int replans = 0;
  for (int trip = 0; trip < 25; ++trip) {
    CostOverlay overlay(g);
    overlay.set_signal_delay(g, 20.0);
    const TravelCost cost(g, overlay, {120.0 / 3.6});
    const std::vector<EdgePoint> goals = with_twin(g, random_point(g, rng));
    std::vector<EdgePoint> starts = with_twin(g, random_point(g, rng));
    AnyDStarLite dstar(std::get<1>(GetParam()), cost, starts, goals);
    dstar.replan();
    for (int step = 0; step < 20; ++step) {
      Route r = dstar.route();
      if (!r.found || r.edges.size() < 3) break;
      std::vector<EdgeId> changed;
      for (int k = 0; k < 10; ++k) {
        const EdgeId e = unit(rng) < 0.4 ? r.edges[std::uniform_int_distribution<std::size_t>(1, r.edges.size() - 1)(rng)]
                                         : random_point(g, rng).edge;
        if (unit(rng) < 0.3) {
          overlay.reset_edge(e);
        } else {
          overlay.set_edge(e, {1.0 + 4.0 * unit(rng), 30.0 * unit(rng)});
        }
        changed.push_back(e);
      }
      starts = {{r.edges[1], g.length_m(r.edges[1]) * unit(rng)}};
      dstar.move_start(starts);
      dstar.changed(changed, {});
      dstar.replan();
      expect_matches_dijkstra(dstar, cost, starts, goals, std::string(map) + " trip " + std::to_string(trip));
      ++replans;
      if (::testing::Test::HasFailure()) return;
    }
  }
  EXPECT_GT(replans, 100);
}

INSTANTIATE_TEST_SUITE_P(RealMaps, DStarLiteOnExtract,
                         ::testing::Combine(::testing::Values("monaco.osm.gz", "andorra.osm.pbf", "liechtenstein.osm.pbf"),
                                            ::testing::Values(Variant::eager, Variant::cch)),
                         [](const ::testing::TestParamInfo<std::tuple<const char*, Variant>>& p) {
                           std::string name = std::get<0>(p.param);
                           name = name.substr(0, name.find('.'));
                           return name + (std::get<1>(p.param) == Variant::cch ? "_cch" : "");
                         });

}  // namespace
}  // namespace corridor::planner
