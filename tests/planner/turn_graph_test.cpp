// The turn graph against the restrictions themselves: every route found must be legal when read
// against the restriction paths the graph was built from, by a checker that does not use the turn
// graph. The randomized search oracles cannot see this (all three searches share the turn graph).
#include "maps/turn_graph.hpp"

#include <gtest/gtest.h>

#include <random>

#include "planner/dstar_lite.hpp"
#include "planner/one_to_one_search.hpp"
#include "tests/planner/test_graphs.hpp"

namespace corridor::planner {
namespace {

bool binds(const VehicleProfile& p, const maps::TurnRestrictions& r, std::size_t k) {
  const bool mode = (p.restriction_modes & maps::mode_bit(maps::RestrictionMode{r.mode[k]})) != 0;
  return mode && (r.except[k] & p.except_classes) == 0;
}

// Empty when `driven` obeys every binding restriction; else which one it breaks and where.
std::string violation(const maps::RoadGraph& g, const VehicleProfile& p, const std::vector<EdgeId>& driven) {
  const auto& r = g.data().restrictions;
  for (std::size_t k = 0; k < r.size(); ++k) {
    if (!binds(p, r, k)) continue;
    const std::span<const EdgeId> path(r.edges.data() + r.first[k], r.first[k + 1] - r.first[k]);
    for (std::size_t j = 0; j < driven.size(); ++j) {
      if (driven[j] != path[0]) continue;
      std::size_t i = 1;
      while (i < path.size() && j + i < driven.size() && driven[j + i] == path[i]) ++i;
      const bool whole = i == path.size();
      const bool left_an_only = r.only[k] != 0 && i < path.size() && j + i < driven.size();
      if ((r.only[k] == 0 && whole) || left_an_only) {
        return "restriction " + std::to_string(k) + (r.only[k] != 0 ? " (only_)" : " (no_)") + " at route edge " +
               std::to_string(j);
      }
    }
  }
  return {};
}

// Random restrictions, with at most one only_ restriction per from edge: two only_ restrictions
// from one edge allow the union of their exits in the graph, which the checker does not model.
maps::RoadGraph restricted_grid(std::uint64_t seed) {
  const auto grid = testing::random_grid(seed, 9, 9);
  const auto raw = testing::with_random_restrictions(grid, seed, grid.edge_count() / 4);
  maps::RoadGraphData d = raw.data();
  const auto& all = raw.data().restrictions;
  d.restrictions = {};
  std::vector<EdgeId> only_from;
  for (std::size_t k = 0; k < all.size(); ++k) {
    const std::vector<EdgeId> path(all.edges.begin() + all.first[k], all.edges.begin() + all.first[k + 1]);
    if (all.only[k] != 0) {
      if (std::find(only_from.begin(), only_from.end(), path[0]) != only_from.end()) continue;
      only_from.push_back(path[0]);
    }
    d.restrictions.add(path, all.only[k] != 0, maps::RestrictionMode{all.mode[k]}, all.except[k]);
  }
  return maps::RoadGraph(std::move(d));
}

TEST(TurnGraph, EveryRouteObeysEveryBindingRestriction) {
  std::size_t routes = 0, copies = 0;
  for (std::uint64_t seed = 1; seed <= 40; ++seed) {
    const auto g = restricted_grid(seed);
    copies += g.turns().copy_count();
    const CostOverlay overlay(g);
    const VehicleProfile profile = testing::oracle_profile(seed, 30.0);
    const TravelCost cost(g, overlay, profile);
    std::mt19937_64 rng(seed);
    OneToOneSearch search;
    for (int q = 0; q < 40; ++q) {
      const EdgePoint s = testing::random_point(g, rng);
      const EdgePoint t = testing::random_point(g, rng);
      const Route r = search.run(SearchSpace(cost, {s}, {t}), false);
      if (!r.found) continue;
      ++routes;
      ASSERT_EQ(violation(g, profile, r.edges), "") << "seed " << seed << " query " << q;
    }
  }
  EXPECT_GT(routes, 800u);
  EXPECT_GT(copies, 100u);  // via-way restrictions were exercised
}

// A vehicle that has entered a via-way restriction's path stays bound by it after a replan: the
// start carries its turn-graph state (Route::point_on). Checked on the whole drive, the part
// already driven and each replanned rest together.
TEST(TurnGraph, AReplanFromARouteKeepsWhatARestrictionRemembers) {
  std::size_t replans = 0;
  for (std::uint64_t seed = 1; seed <= 40; ++seed) {
    const auto g = restricted_grid(seed + 100);
    CostOverlay overlay(g);
    const VehicleProfile profile = testing::oracle_profile(seed, 30.0);
    const TravelCost cost(g, overlay, profile);
    std::mt19937_64 rng(seed);
    const EdgePoint goal = testing::random_point(g, rng);
    DStarLite dstar(cost, {testing::random_point(g, rng)}, {goal});
    dstar.replan();
    Route route = dstar.route();
    std::vector<EdgeId> driven;
    for (int step = 0; step < 30 && route.found && route.edges.size() > 1; ++step) {
      // Drive onto the next edge, and make the edges just behind the vehicle expensive, so the
      // replan looks for another way on.
      driven.push_back(route.edges[0]);
      const EdgePoint at = route.point_on(1, 0.0);
      std::vector<EdgeId> changed;
      for (EdgeId e : g.out_edges(g.head(route.edges[1]))) {
        overlay.set_edge(e, {1.0 + std::uniform_real_distribution<double>(0, 8)(rng), 0.0});
        changed.push_back(e);
      }
      dstar.move_start({at});
      dstar.edges_changed(changed);
      dstar.replan();
      route = dstar.route();
      ++replans;
      if (!route.found) break;
      std::vector<EdgeId> whole = driven;
      whole.insert(whole.end(), route.edges.begin(), route.edges.end());
      ASSERT_EQ(violation(g, profile, whole), "") << "seed " << seed << " step " << step;
    }
  }
  EXPECT_GT(replans, 300u);
}

// Two via-way restrictions where one's path contains the other's start: no_(A, B, C) and
// no_(X, A, B, Y). In either file order, only traffic that came from X is barred from A -> B -> Y,
// and traffic from X is barred from A -> B -> C too. (Inserting the longer one by following the
// shorter one's copy used to bar A -> B -> Y for everyone in one order.)
TEST(TurnGraph, NestedViaWayRestrictionsBindOnlyTheirOwnHistories) {
  const auto grid = testing::random_grid(7, 6, 6);
  EdgeId X, A, B, C, Y;
  bool found = false;
  for (EdgeId a : grid.edges()) {
    for (EdgeId x : grid.in_edges(grid.tail(a))) {
      for (EdgeId b : grid.out_edges(grid.head(a))) {
        std::vector<EdgeId> exits;
        for (EdgeId f : grid.out_edges(grid.head(b))) {
          if (f != grid.twin(b)) exits.push_back(f);
        }
        if (found || x == grid.twin(a) || b == grid.twin(a) || exits.size() < 2) continue;
        X = x, A = a, B = b, C = exits[0], Y = exits[1];
        found = true;
      }
    }
  }
  ASSERT_TRUE(found);
  for (bool short_first : {true, false}) {
    maps::RoadGraphData d = grid.data();
    d.restrictions = {};
    const std::vector<EdgeId> shorter{A, B, C}, longer{X, A, B, Y};
    d.restrictions.add(short_first ? shorter : longer, false, maps::RestrictionMode::all, false);
    d.restrictions.add(short_first ? longer : shorter, false, maps::RestrictionMode::all, false);
    const maps::RoadGraph g(std::move(d));
    const CostOverlay overlay(g);
    const TravelCost cost(g, overlay, testing::free_turns(30.0));
    const std::uint32_t on_b = cost.turn_onto(A.v, B).second;  // came onto A from elsewhere
    EXPECT_LT(cost.turn_onto(on_b, Y).first, kInfCost) << "A -> B -> Y barred for everyone, short_first=" << short_first;
    EXPECT_EQ(cost.turn_onto(on_b, C).first, kInfCost) << short_first;
    const std::uint32_t from_x = cost.turn_onto(cost.turn_onto(X.v, A).second, B).second;
    EXPECT_EQ(cost.turn_onto(from_x, Y).first, kInfCost) << short_first;
    EXPECT_EQ(cost.turn_onto(from_x, C).first, kInfCost) << short_first;
  }
}

}  // namespace
}  // namespace corridor::planner
