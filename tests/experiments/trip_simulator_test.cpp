#include "planner/experiments/trip_simulator.hpp"

#include <gtest/gtest.h>

#include "maps/map_loader.hpp"
#include "planner/experiments/analytical_graph.hpp"
#include "planner/experiments/scenario_generator.hpp"
#include "planner/one_to_one_search.hpp"

namespace corridor::planner {
namespace {

EdgeId edge_between(const AnalyticalGraph& g, const char* from, const char* to) {
  const NodeId a = *g.find(from);
  const NodeId b = *g.find(to);
  for (EdgeId e : g.graph.out_edges(a)) {
    if (g.graph.head(e) == b) return e;
  }
  throw std::logic_error("no such edge");
}

std::vector<std::string> names(const AnalyticalGraph& g, const std::vector<EdgeId>& edges) {
  std::vector<std::string> out{g.name_of(g.graph.tail(edges.front()))};
  for (EdgeId e : edges) out.push_back(g.name_of(g.graph.head(e)));
  return out;
}

// Simple graph, 120 km/h (1 km = 30 s), 3 min at every signal. The upper corridor b-c-d is 4.6 km
// with one signal (c); the lower b-e-f-d is 4.8 km with two (e, f); a-b is 2 km.
// A 4-minute jam appears on b-c at 30 s (before the vehicle reaches b at 60 s) and on c-d at 100 s.
struct SimpleCase {
  AnalyticalGraph g = *builtin_analytical_graph("simple");
  TripScenario scenario{g.source, g.destination, std::vector<double>(g.graph.node_count(), 180.0),
                        {{100.0, edge_between(g, "c", "d"), 240.0}, {30.0, edge_between(g, "b", "c"), 240.0}}};
};

TEST(TripSimulator, SimpleGraphTravelTimesEqualHandComputedValues) {
  SimpleCase c;
  const VehicleProfile v{120.0 / 3.6};
  // Static, no preemption: 60 to b, 180 signal + 69 + 240 jam to c (t=549, c-d jammed since 100),
  // 180 signal + 69 + 240 to d.
  const TripResult sn = drive_trip(c.g.graph, c.scenario, Routing::static_route, Signals::no_preemption, v);
  EXPECT_NEAR(sn.travel_time_s, 1038.0, 1e-3);
  EXPECT_NEAR(sn.signal_wait_s, 360.0, 1e-9);
  EXPECT_NEAR(sn.queue_wait_s, 480.0, 1e-9);
  EXPECT_EQ(names(c.g, sn.driven), (std::vector<std::string>{"a", "b", "c", "d"}));
  EXPECT_FALSE(sn.rerouted());
  // Dynamic, no preemption: at b (t=60) it knows of b-c: 180+69+240+180+69 = 738 via c against
  // 180+57+180+30+180+57 = 684 via e and f, so it turns: 60 + 684.
  const TripResult dn = drive_trip(c.g.graph, c.scenario, Routing::dynamic_route, Signals::no_preemption, v);
  EXPECT_NEAR(dn.travel_time_s, 744.0, 1e-3);
  EXPECT_EQ(names(c.g, dn.driven), (std::vector<std::string>{"a", "b", "e", "f", "d"}));
  EXPECT_TRUE(dn.rerouted());
  EXPECT_EQ(dn.replans, 2u);  // at b, and at e for the c-d jam, which is off its new route
  EXPECT_EQ(dn.route_changes, 1u);
  // Static with preemption: no signal waits; c-d is jammed when it gets to c at t=369.
  const TripResult sp = drive_trip(c.g.graph, c.scenario, Routing::static_route, Signals::preemption, v);
  EXPECT_NEAR(sp.travel_time_s, 60.0 + 69.0 + 240.0 + 69.0 + 240.0, 1e-3);
  EXPECT_EQ(sp.signal_wait_s, 0.0);
  // Dynamic with preemption: 69+240+69 via c against 57+30+57 = 144 via e and f.
  const TripResult dp = drive_trip(c.g.graph, c.scenario, Routing::dynamic_route, Signals::preemption, v);
  EXPECT_NEAR(dp.travel_time_s, 204.0, 1e-3);
  EXPECT_EQ(dp.queue_wait_s, 0.0);
}

TEST(TripSimulator, JamThatAppearsAfterTheDecisionCannotBeAvoided) {
  SimpleCase c;
  c.scenario.events = {{61.0, edge_between(c.g, "b", "c"), 240.0}};  // the vehicle committed at 60 s
  const VehicleProfile v{120.0 / 3.6};
  const TripResult s = drive_trip(c.g.graph, c.scenario, Routing::static_route, Signals::preemption, v);
  const TripResult d = drive_trip(c.g.graph, c.scenario, Routing::dynamic_route, Signals::preemption, v);
  EXPECT_NEAR(s.travel_time_s, 198.0, 1e-3);
  EXPECT_NEAR(d.travel_time_s, 198.0, 1e-3);
  EXPECT_EQ(d.replans, 1u);  // told at c, too late to matter
  EXPECT_EQ(d.route_changes, 0u);
}

TEST(TripSimulator, LaterEventOnTheSameEdgeReplacesTheEarlierOne) {
  const std::vector<CongestionEvent> events{{10.0, EdgeId{3}, 50.0}, {20.0, EdgeId{3}, 0.0}, {15.0, EdgeId{4}, 7.0}};
  std::vector<CongestionEvent> sorted = events;
  std::sort(sorted.begin(), sorted.end(), [](auto& a, auto& b) { return a.time_s < b.time_s; });
  EXPECT_EQ(queue_delay_at(sorted, EdgeId{3}, 5.0), 0.0);
  EXPECT_EQ(queue_delay_at(sorted, EdgeId{3}, 10.0), 50.0);
  EXPECT_EQ(queue_delay_at(sorted, EdgeId{3}, 25.0), 0.0);
  EXPECT_EQ(queue_delay_at(sorted, EdgeId{4}, 25.0), 7.0);
}

TEST(TripSimulator, WithoutCongestionStaticEqualsDynamicForEveryPairOfTheComplexGraph) {
  const auto g = *builtin_analytical_graph("complex");
  Rng rng(7);
  for (NodeId s : g.graph.nodes()) {
    for (NodeId t : g.graph.nodes()) {
      if (s == t) continue;
      const TripScenario sc{s, t, draw_signal_delays(g.graph, {0.0, 180.0}, rng), {}};
      for (Signals sig : {Signals::no_preemption, Signals::preemption}) {
        const TripResult a = drive_trip(g.graph, sc, Routing::static_route, sig, {});
        const TripResult b = drive_trip(g.graph, sc, Routing::dynamic_route, sig, {});
        EXPECT_NEAR(a.travel_time_s, b.travel_time_s, 1e-9) << g.name_of(s) << "-" << g.name_of(t);
        EXPECT_EQ(b.replans, 0u);
      }
    }
  }
}

TEST(TripSimulator, RejectsBadScenarios) {
  const auto g = *builtin_analytical_graph("simple");
  const std::vector<double> delays(g.graph.node_count(), 0.0);
  EXPECT_THROW(drive_trip(g.graph, {g.source, g.source, delays, {}}, Routing::static_route, Signals::preemption, {}),
               std::invalid_argument);
  EXPECT_THROW(drive_trip(g.graph, {g.source, NodeId{99}, delays, {}}, Routing::static_route, Signals::preemption, {}),
               std::invalid_argument);
  EXPECT_THROW(drive_trip(g.graph, {g.source, g.destination, {1.0}, {}}, Routing::static_route, Signals::preemption, {}),
               std::invalid_argument);
  EXPECT_THROW(drive_trip(g.graph, {g.source, g.destination, delays, {{1.0, EdgeId{999}, 1.0}}}, Routing::static_route,
                          Signals::preemption, {}),
               std::invalid_argument);
  EXPECT_THROW(drive_trip(g.graph, {g.source, g.destination, delays, {{1.0, EdgeId{0}, -1.0}}}, Routing::static_route,
                          Signals::preemption, {}),
               std::invalid_argument);
}

// The property of the issue: at every replan the dynamic vehicle's cost-to-goal, and the cost of the
// route it follows, equal Dijkstra's from scratch on the costs known at that moment.
std::uint64_t check_replans_against_dijkstra(const maps::RoadGraph& graph, std::uint32_t seeds, double min_pair_m,
                                             std::uint32_t min_edges) {
  std::uint64_t checked = 0;
  OneToOneSearch dijkstra;
  for (std::uint32_t seed = 1; seed <= seeds; ++seed) {
    Rng rng(seed);
    const auto [s, t] = draw_pair(graph, min_pair_m, min_edges, {}, rng);
    TripScenario sc{s, t, draw_signal_delays(graph, {0.0, 180.0}, rng), {}};
    const Route plan = static_plan(graph, sc, Signals::no_preemption, {});
    sc.events = draw_events(pick_congestion_sites(graph, plan, {3, 3}, rng), {0.0, 420.0}, rng);
    const Signals signals = seed % 2 == 0 ? Signals::preemption : Signals::no_preemption;
    const ReplanObserver check = [&](const DStarLite& planner, const TravelCost& known) {
      const SearchSpace space(known, {planner.space().starts().begin(), planner.space().starts().end()},
                              {planner.space().goals().begin(), planner.space().goals().end()});
      const Route oracle = dijkstra.run(space, false);
      ASSERT_TRUE(oracle.found);
      ASSERT_NEAR(planner.cost_to_goal_s(), oracle.travel_time_s, 1e-9 * oracle.travel_time_s) << "seed " << seed;
      ASSERT_NEAR(planner.route().travel_time_s, oracle.travel_time_s, 1e-9 * oracle.travel_time_s) << "seed " << seed;
      ++checked;
    };
    const TripResult r = drive_trip(graph, sc, Routing::dynamic_route, signals, {}, check);
    if (::testing::Test::HasFatalFailure()) return checked;
    EXPECT_GT(r.travel_time_s, 0.0);
  }
  return checked;
}

TEST(TripSimulator, EveryReplanMatchesDijkstraOnKnownCostsOnTheComplexGraph) {
  const auto g = *builtin_analytical_graph("complex");
  EXPECT_GT(check_replans_against_dijkstra(g.graph, 5000, 0.0, 2), 15000u);
}

TEST(TripSimulator, EveryReplanMatchesDijkstraOnKnownCostsOnMonaco) {
  const maps::RoadGraph monaco = maps::load_map(CORRIDOR_DEFAULT_MAP, {});
  EXPECT_GT(check_replans_against_dijkstra(monaco, 3000, 1000.0, 4), 30000u);
}

}  // namespace
}  // namespace corridor::planner
