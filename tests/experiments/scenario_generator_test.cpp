#include "planner/experiments/scenario_generator.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <set>

#include "maps/synthetic_grid.hpp"

namespace corridor::planner {
namespace {

TEST(Rng, SameSeedSameSequenceAndUniformStaysInRange) {
  Rng a(42);
  Rng b(42);
  Rng c(43);
  bool differs = false;
  for (int i = 0; i < 1000; ++i) {
    const double x = a.uniform();
    EXPECT_EQ(x, b.uniform());
    differs = differs || x != c.uniform();
    EXPECT_GE(x, 0.0);
    EXPECT_LT(x, 1.0);
    const auto k = a.below(7);
    b.below(7);
    EXPECT_LT(k, 7u);
  }
  EXPECT_TRUE(differs);
  EXPECT_EQ(Rng(1).uniform(3.0, 3.0), 3.0);
  EXPECT_THROW(Rng(1).below(0), std::invalid_argument);
}

TEST(Rng, DerivedSeedsDependOnSeedAndStream) {
  EXPECT_EQ(derive_seed(1, "complex/fig7"), derive_seed(1, "complex/fig7"));
  EXPECT_NE(derive_seed(1, "complex/fig7"), derive_seed(2, "complex/fig7"));
  EXPECT_NE(derive_seed(1, "complex/fig7"), derive_seed(1, "complex/fig9"));
}

TEST(ScenarioGenerator, SignalDelaysOnlyAtSignalizedIntersectionsWithinRange) {
  maps::GridSpec spec;
  spec.signal_fraction = 0.4;
  const auto g = maps::make_perturbed_grid(spec);
  Rng rng(3);
  const auto d = draw_signal_delays(g, {30.0, 90.0}, rng);
  ASSERT_EQ(d.size(), g.node_count());
  for (NodeId v : g.nodes()) {
    if (g.signalized(v)) {
      EXPECT_GE(d[v.index()], 30.0);
      EXPECT_LE(d[v.index()], 90.0);
    } else {
      EXPECT_EQ(d[v.index()], 0.0);
    }
  }
}

TEST(ScenarioGenerator, CongestionAppearsOnTheRouteBeforeTheVehicleGetsThereAndNearItOffTheRoute) {
  maps::GridSpec spec;
  spec.rows = spec.cols = 12;
  const auto g = maps::make_perturbed_grid(spec);
  for (std::uint64_t seed = 1; seed <= 200; ++seed) {
    Rng rng(seed);
    const auto [s, t] = draw_pair(g, 800.0, 4, {}, rng);
    const TripScenario sc{s, t, draw_signal_delays(g, {0.0, 60.0}, rng), {}};
    const Route plan = static_plan(g, sc, Signals::no_preemption, {});
    const CongestionSites sites = pick_congestion_sites(g, plan, {3, 3}, rng);
    ASSERT_EQ(sites.edges.size(), sites.reach_s.size());
    std::set<EdgeId> unique(sites.edges.begin(), sites.edges.end());
    EXPECT_EQ(unique.size(), sites.edges.size()) << "an edge was picked twice";
    std::size_t on_route = 0;
    for (std::size_t i = 0; i < sites.edges.size(); ++i) {
      const EdgeId e = sites.edges[i];
      const auto it = std::find(plan.edges.begin(), plan.edges.end(), e);
      if (it != plan.edges.end()) {
        ++on_route;
        ASSERT_NE(it, plan.edges.begin()) << "the first edge is already being driven";
        const auto k = static_cast<std::size_t>(it - plan.edges.begin());
        EXPECT_DOUBLE_EQ(sites.reach_s[i], plan.arrival_s[k - 1]);
      } else {
        EXPECT_DOUBLE_EQ(sites.reach_s[i], plan.arrival_s.back());
      }
    }
    EXPECT_EQ(on_route, std::min<std::size_t>(3, plan.edges.size() - 1));
    const auto events = draw_events(sites, {0.0, 420.0}, rng);
    ASSERT_EQ(events.size(), sites.edges.size());
    for (std::size_t i = 0; i < events.size(); ++i) {
      EXPECT_GT(events[i].time_s, 0.0);
      EXPECT_LE(events[i].time_s, sites.reach_s[i]);
      EXPECT_GE(events[i].queue_delay_s, 0.0);
      EXPECT_LE(events[i].queue_delay_s, 420.0);
    }
  }
}

TEST(ScenarioGenerator, PairsAreFarEnoughApartAndImpossibleRequestsFail) {
  maps::GridSpec spec;
  const auto g = maps::make_perturbed_grid(spec);
  Rng rng(5);
  for (int i = 0; i < 50; ++i) {
    const auto [s, t] = draw_pair(g, 1000.0, 3, {}, rng);
    EXPECT_GE(maps::distance_m(g.position(s), g.position(t)), 1000.0);
  }
  EXPECT_THROW(draw_pair(g, 1e7, 3, {}, rng), std::runtime_error);
}

}  // namespace
}  // namespace corridor::planner

namespace corridor::planner {
namespace {

TEST(ScenarioGenerator, JunctionsAreNodesJoiningAtLeastThreeRoads) {
  maps::RoadGraphData d;
  // a - b - c, and b - e: only b is a junction; two-way roads count once per neighbour.
  d.origin = {47.0, 9.5};
  d.node_x_m = {0, 100, 200, 100};
  d.node_y_m = {0, 0, 0, 100};
  d.node_osm_id = {OsmNodeId{1}, OsmNodeId{2}, OsmNodeId{3}, OsmNodeId{4}};
  d.node_signalized = {0, 0, 0, 0};
  const std::vector<std::pair<std::uint32_t, std::uint32_t>> arcs{{0, 1}, {1, 0}, {1, 2}, {1, 3}, {2, 1}, {3, 1}};
  d.first_out = {0, 1, 4, 5, 6};
  d.geometry_first = {0};
  for (auto [u, v] : arcs) {
    d.edge_tail.push_back(NodeId{u});
    d.edge_head.push_back(NodeId{v});
    d.edge_length_m.push_back(100.0);
    d.edge_speed_mps.push_back(10.0f);
    d.edge_osm_way.push_back(OsmWayId{1});
    d.edge_class.push_back(maps::RoadClass::residential);
    d.edge_twin.push_back(kInvalidEdge);
    d.geometry.push_back({d.node_x_m[u], d.node_y_m[u]});
    d.geometry.push_back({d.node_x_m[v], d.node_y_m[v]});
    d.geometry_first.push_back(static_cast<std::uint32_t>(d.geometry.size()));
  }
  maps::build_reverse_adjacency(d);
  const maps::RoadGraph g(std::move(d));
  EXPECT_EQ(junction_mask(g), (std::vector<std::uint8_t>{0, 1, 0, 0}));
  Rng rng(1);
  const auto delays = draw_signal_delays(junction_mask(g), {180.0, 180.0}, rng);
  EXPECT_EQ(delays, (std::vector<double>{0.0, 180.0, 0.0, 0.0}));
}

}  // namespace
}  // namespace corridor::planner
