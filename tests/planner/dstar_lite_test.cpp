#include "planner/dstar_lite.hpp"

#include <gtest/gtest.h>

#include <random>

#include "planner/one_to_one_search.hpp"
#include "tests/planner/test_graphs.hpp"

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
void expect_matches_dijkstra(const DStarLite& dstar, const TravelCost& cost, const std::vector<EdgePoint>& starts,
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

TEST(DStarLite, InitialPlanMatchesDijkstraOnRandomGraphs) {
  for (std::uint64_t seed = 1; seed <= 60; ++seed) {
    const auto g = random_grid(seed, 8, 9);
    CostOverlay overlay(g);
    overlay.set_signal_delay(g, 7.5);
    const TravelCost cost(g, overlay, {30.0});
    std::mt19937_64 rng(seed);
    for (int q = 0; q < 10; ++q) {
      const auto starts = with_twin(g, random_point(g, rng));
      const auto goals = with_twin(g, random_point(g, rng));
      DStarLite dstar(cost, starts, goals);
      dstar.replan();
      expect_matches_dijkstra(dstar, cost, starts, goals, "seed " + std::to_string(seed));
    }
  }
}

// Thousands of random update sequences: cost increases and decreases on and off the route,
// closures and reopenings, node delay changes, and start moves, checked after every replan.
TEST(DStarLite, ReplanMatchesDijkstraAfterRandomUpdateSequences) {
  int replans = 0;
  constexpr std::uint64_t kSequences = 200;
  for (std::uint64_t seed = 1; seed <= kSequences; ++seed) {
    const auto g = random_grid(seed, 7, 7 + seed % 4);
    CostOverlay overlay(g);
    const TravelCost cost(g, overlay, {25.0});
    std::mt19937_64 rng(seed * 7919);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    auto starts = with_twin(g, random_point(g, rng));
    const auto goals = std::vector<EdgePoint>{random_point(g, rng)};
    DStarLite dstar(cost, starts, goals);
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
      dstar.edges_changed(edges);
      dstar.nodes_changed(nodes);
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

}  // namespace
}  // namespace corridor::planner
