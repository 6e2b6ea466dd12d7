#include "planner/one_to_one_search.hpp"

#include <gtest/gtest.h>

#include <random>

#include "tests/planner/test_graphs.hpp"
#include "tests/planner/test_graphs_line.hpp"

namespace corridor::planner {
namespace {

using testing::diamond;
using testing::edge_from_to;

// Hand-computed: from the middle of A->B to the middle of B->C is 5 s + B's delay + 5 s.
TEST(OneToOneSearch, HandComputedRouteThroughASignal) {
  const auto g = diamond();
  CostOverlay overlay(g);
  overlay.set_signal_delay(g, 7.0);
  const TravelCost cost(g, overlay, {30.0});
  const EdgePoint start{edge_from_to(g, 1, 2), 50.0};
  const EdgePoint goal{edge_from_to(g, 2, 3), 50.0};
  for (bool astar : {false, true}) {
    OneToOneSearch search;
    const Route r = search.run(SearchSpace(cost, {start}, {goal}), astar);
    ASSERT_TRUE(r.found);
    EXPECT_DOUBLE_EQ(r.travel_time_s, 17.0);
    EXPECT_DOUBLE_EQ(r.length_m, 100.0);
    ASSERT_EQ(r.nodes.size(), 1u);
    EXPECT_EQ(g.osm_node(r.nodes[0]).v, 2);
    EXPECT_DOUBLE_EQ(r.arrival_s[0], 5.0);
    EXPECT_DOUBLE_EQ(*r.cost_to_goal_s(r.nodes[0]), 12.0);
  }
}

// Congest B->C threefold: the remaining half costs 15 s, still cheaper than turning around.
TEST(OneToOneSearch, HandComputedRouteUnderCongestion) {
  const auto g = diamond();
  CostOverlay overlay(g);
  overlay.set_signal_delay(g, 7.0);
  overlay.set_edge(edge_from_to(g, 2, 3), {3.0, 0.0});
  const TravelCost cost(g, overlay, {30.0});
  OneToOneSearch search;
  const Route r = search.run(SearchSpace(cost, {{edge_from_to(g, 1, 2), 50.0}}, {{edge_from_to(g, 2, 3), 50.0}}), true);
  EXPECT_DOUBLE_EQ(r.travel_time_s, 5.0 + 7.0 + 15.0);
}

// Start at A (both directions allowed), goal at C: via D is 2 × 141.42 m at 20 m/s = 14.14 s,
// via B is 20 s plus B's delay.
TEST(OneToOneSearch, PrefersTheFasterDetour) {
  const auto g = diamond();
  const CostOverlay overlay(g);
  const TravelCost cost(g, overlay, testing::free_turns(30.0));
  const EdgeId ab = edge_from_to(g, 1, 2), ad = edge_from_to(g, 1, 4);
  const EdgeId dc = edge_from_to(g, 4, 3), bc = edge_from_to(g, 2, 3);
  OneToOneSearch search;
  const Route r = search.run(SearchSpace(cost, {{ab, 0.0}, {ad, 0.0}}, {{bc, 100.0}, {dc, g.length_m(dc)}}), false);
  EXPECT_NEAR(r.travel_time_s, 2 * std::sqrt(2.0) * 100.0 / 20.0, 1e-9);
  EXPECT_EQ(r.edges, (std::vector<EdgeId>{ad, dc}));
}

TEST(OneToOneSearch, StartAndGoalOnOneEdge) {
  const auto g = diamond();
  const CostOverlay overlay(g);
  const TravelCost cost(g, overlay, testing::free_turns(30.0));
  const EdgeId ab = edge_from_to(g, 1, 2);
  OneToOneSearch search;
  const Route ahead = search.run(SearchSpace(cost, {{ab, 20.0}}, {{ab, 70.0}}), true);
  EXPECT_DOUBLE_EQ(ahead.travel_time_s, 5.0);
  EXPECT_EQ(ahead.edges, std::vector<EdgeId>{ab});
  // A goal behind the start on the same one-directional edge needs a loop: B -> A -> B again.
  const Route behind = search.run(SearchSpace(cost, {{ab, 70.0}}, {{ab, 20.0}}), true);
  EXPECT_NEAR(behind.travel_time_s, 3.0 + 10.0 + 2.0, 1e-9);
  EXPECT_EQ(behind.edges.size(), 3u);
}

TEST(OneToOneSearch, UnreachableGoalIsNotFound) {
  const auto g = diamond();
  CostOverlay overlay(g);
  for (auto [a, b] : {std::pair{1, 2}, std::pair{1, 4}, std::pair{3, 2}, std::pair{3, 4}}) {
    overlay.close_edge(edge_from_to(g, a, b));
  }
  const TravelCost cost(g, overlay, {30.0});
  OneToOneSearch search;
  const Route r = search.run(SearchSpace(cost, {{edge_from_to(g, 2, 1), 0.0}}, {{edge_from_to(g, 2, 3), 50.0}}), true);
  EXPECT_FALSE(r.found);
  EXPECT_EQ(r.travel_time_s, kInfCost);
}

TEST(OneToOneSearch, AStarMatchesDijkstraOnRandomGraphs) {
  for (std::uint64_t seed = 1; seed <= 40; ++seed) {
    const auto grid = testing::random_grid(seed, 10, 10);
    const auto g = testing::with_random_stops(testing::with_random_restrictions(grid, seed, grid.edge_count() / 6), seed, 10);
    CostOverlay overlay(g);
    overlay.set_signal_delay(g, 12.0);
    std::mt19937_64 rng(seed);
    for (EdgeId e : g.edges()) {
      if (rng() % 5 == 0) overlay.set_edge(e, {1.0 + static_cast<double>(rng() % 40) / 10.0, static_cast<double>(rng() % 30)});
    }
    const TravelCost cost(g, overlay, testing::oracle_profile(seed, 33.0));
    OneToOneSearch a, d;
    for (int q = 0; q < 20; ++q) {
      const SearchSpace space(cost, testing::with_twin(g, testing::random_point(g, rng)),
                              testing::with_twin(g, testing::random_point(g, rng)));
      SearchStats sa, sd;
      const Route ra = a.run(space, true, &sa);
      const Route rd = d.run(space, false, &sd);
      ASSERT_EQ(ra.found, rd.found);
      if (rd.found) {
        EXPECT_NEAR(ra.travel_time_s, rd.travel_time_s, 1e-9 * std::max(1.0, rd.travel_time_s));
      }
      EXPECT_LE(sa.settled, sd.settled);  // the heuristic never makes A* search more
    }
  }
}

TEST(OneToOneSearch, InvalidEndpointsAreRejected) {
  const auto g = diamond();
  const CostOverlay overlay(g);
  const TravelCost cost(g, overlay, {30.0});
  EXPECT_THROW(SearchSpace(cost, {}, {{EdgeId{0}, 0.0}}), std::invalid_argument);
  EXPECT_THROW(SearchSpace(cost, {{EdgeId{77}, 0.0}}, {{EdgeId{0}, 0.0}}), std::invalid_argument);
  EXPECT_THROW(SearchSpace(cost, {{EdgeId{0}, std::nan("")}}, {{EdgeId{0}, 0.0}}), std::invalid_argument);
}

}  // namespace
}  // namespace corridor::planner
