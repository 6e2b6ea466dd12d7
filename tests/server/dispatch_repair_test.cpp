// Who repairs the missions' plans and on which graph changes how, never what: concurrent
// reports, the repair threads and their priority, and the hierarchy against the turn graph.
#include "server/dispatch_service.hpp"

#include <pthread.h>
#include <sched.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <map>
#include <numeric>
#include <random>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "maps/intersection_geometry.hpp"
#include "planner/one_to_one_search.hpp"
#include "preemption/signal_costs.hpp"
#include "tests/server/dispatch_fixture.hpp"
#include "tests/server/temp_db.hpp"

namespace corridor::server {
namespace {

using testing::code_of;
using testing::corner;
using testing::grid;
using testing::node_ll;
using testing::request;

// Missions are served in parallel (one lock per mission), so several threads post positions,
// congestion, counts and reads at once; afterwards every plan must still be the optimal route
// under the final costs (the Dijkstra oracle), and every position must be stored. Run under TSan too.
class ConcurrentReports : public ::testing::TestWithParam<PlannerGraph> {};

TEST_P(ConcurrentReports, KeepEveryPlanOptimal) {
  TempDb db;
  Store store(db.path());
  DispatchConfig config;
  config.planner_graph = GetParam();
  DispatchService service(grid(), config, &store, 0.0);
  ASSERT_EQ(service.planner_graph(), GetParam());
  const auto n = static_cast<std::uint32_t>(grid().node_count());
  std::mt19937 rng(5);
  const auto pick = [&](std::uint32_t from) { return NodeId{from + static_cast<std::uint32_t>(rng() % (n / 2))}; };
  std::vector<MissionId> ids;
  for (int i = 0; i < 8; ++i) {
    MissionRequest r = request("amb-" + std::to_string(i));
    r.origin = node_ll(pick(0));
    r.destination = node_ll(pick(n / 2));
    ids.push_back(service.create_mission(r, 0.0).id);
  }
  std::atomic<int> positions{0};
  std::atomic<double> clock{1.0};
  const auto now = [&] { return clock.fetch_add(0.01); };
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&, t] {
      for (int k = 0; k < 150; ++k) {
        for (int v = 2 * t; v < 2 * t + 2; ++v) {
          const MissionView m = service.mission(ids[static_cast<std::size_t>(v)]);
          if (m.state != MissionState::active || m.route.edges.size() < 4) continue;
          // Mostly on its current edge; now and then half way along the next one: it drives on.
          const EdgeId e = m.route.edges[k % 10 == 9 ? 1 : 0];
          PositionReport p;
          p.vehicle_id = m.vehicle_id;
          p.position = grid().projection().to_lat_lon(grid().point_along(e, grid().length_m(e) / 2));
          p.timestamp_s = now();
          service.report_position(p, p.timestamp_s).durable->wait();
          ++positions;
        }
      }
    });
  }
  std::map<EdgeId, double> final_factor;  // written by the congestion thread only, read after join
  threads.emplace_back([&] {
    std::mt19937 r(9);
    std::uniform_real_distribution<double> factor(0.6, 6.0);
    for (int k = 0; k < 300; ++k) {
      std::vector<CongestionUpdate> batch;
      for (int j = 0; j < 6; ++j) {
        CongestionUpdate u;
        u.edge = EdgeId{static_cast<std::uint32_t>(r() % grid().edge_count())};
        u.factor = factor(r);
        final_factor[*u.edge] = *u.factor;
        batch.push_back(u);
      }
      service.report_congestion(batch, now());
    }
  });
  threads.emplace_back([&] {
    for (int k = 0; k < 200; ++k) {
      EXPECT_LE(service.missions(MissionState::active).size(), ids.size());
      for (const auto& [node, plan] : service.signal_plans()) {
        EXPECT_FALSE(service.signal_mode(node).first.empty());
        break;
      }
      service.tick(now());
    }
  });
  for (auto& t : threads) t.join();
  service.flush();
  EXPECT_EQ(store.count("positions"), static_cast<std::size_t>(positions.load()));

  planner::CostOverlay overlay(grid());
  overlay.set_signal_delay(grid(), DispatchConfig{}.signal_delay_s);
  // Lights with a plan cost their expected transition: the service preempts them.
  preemption::set_signal_costs(overlay, grid(), maps::default_signal_plans(grid()), preemption::SignalCostRule::preempted);
  for (const auto& [e, f] : final_factor) overlay.set_edge(e, {f, 0.0});
  const planner::TravelCost cost(grid(), overlay, {120.0 / 3.6});
  planner::OneToOneSearch dijkstra;
  int checked = 0;
  for (const MissionView& m : service.missions(MissionState::active)) {
    const auto oracle = dijkstra.run(planner::SearchSpace(cost, {m.route.start}, {m.route.goal}), false);
    EXPECT_NEAR(oracle.travel_time_s, m.route.travel_time_s, 1e-6 * oracle.travel_time_s) << "mission " << m.id;
    ++checked;
  }
  EXPECT_GT(checked, 0);
  EXPECT_GT(positions.load(), 300);
}

INSTANTIATE_TEST_SUITE_P(DispatchService, ConcurrentReports, ::testing::Values(PlannerGraph::turn_graph, PlannerGraph::hierarchy),
                         [](const ::testing::TestParamInfo<PlannerGraph>& p) {
                           return p.param == PlannerGraph::hierarchy ? std::string("hierarchy") : std::string("turn_graph");
                         });

// The repair pool changes who repairs, not what: one thread, four, and two at real-time priority
// give the same routes, and the calling thread leaves a batch with its own scheduling.
TEST(DispatchService, RepairThreadsDoNotChangeTheRepairedRoutes) {
  std::vector<std::vector<std::vector<EdgeId>>> routes;
  for (const auto& [threads, priority] : {std::pair{1, 0}, std::pair{4, 0}, std::pair{2, 1}}) {
    DispatchConfig config;
    config.repair_threads = threads;
    config.repair_realtime_priority = priority;
    DispatchService service(grid(), config, nullptr, 0.0);
    EXPECT_FALSE(service.repair_realtime_granted().has_value());
    int policy_before = -1;
    sched_param param_before{};
    ASSERT_EQ(pthread_getschedparam(pthread_self(), &policy_before, &param_before), 0);
    std::vector<MissionId> ids;
    for (int i = 0; i < 6; ++i) ids.push_back(service.create_mission(request("amb-" + std::to_string(i)), 0.0).id);
    std::vector<CongestionUpdate> updates;
    for (EdgeId e : service.mission(ids[0]).route.edges) {
      CongestionUpdate u;
      u.edge = e;
      u.factor = 4.0;
      updates.push_back(u);
    }
    const CongestionResult r = service.report_congestion(updates, 1.0);
    int policy_after = -1;
    sched_param param_after{};
    ASSERT_EQ(pthread_getschedparam(pthread_self(), &policy_after, &param_after), 0);
    EXPECT_EQ(policy_after, policy_before);
    EXPECT_EQ(param_after.sched_priority, param_before.sched_priority);
    // Granted or not (that is the machine's to say), a configured priority was asked for.
    EXPECT_EQ(service.repair_realtime_granted().has_value(), priority > 0);
    EXPECT_EQ(r.missions_replanned, ids.size());
    EXPECT_EQ(r.routes_changed, ids.size());  // all six share the congested corner-to-corner route
    EXPECT_GT(r.slowest_replan_s, 0.0);
    // No position report ran meanwhile, so the batch repaired every mission itself, and sampled each.
    EXPECT_EQ(r.missions_repaired_by_reports, 0u);
    ASSERT_EQ(r.mission_replan_s.size(), r.missions_replanned - r.missions_repaired_by_reports);
    EXPECT_EQ(*std::max_element(r.mission_replan_s.begin(), r.mission_replan_s.end()), r.slowest_replan_s);
    // The same repairs in CPU time: one per repair, each spent, and none beyond its wall time (the
    // wall window encloses the CPU clock's reads; the thread clock's 1 µs grain gets a margin).
    ASSERT_EQ(r.mission_replan_cpu_s.size(), r.mission_replan_s.size());
    const double cpu_total = std::accumulate(r.mission_replan_cpu_s.begin(), r.mission_replan_cpu_s.end(), 0.0);
    const double wall_total = std::accumulate(r.mission_replan_s.begin(), r.mission_replan_s.end(), 0.0);
    EXPECT_GT(cpu_total, 0.0);
    EXPECT_LE(cpu_total, wall_total + 1e-5 * static_cast<double>(r.missions_replanned));
    routes.emplace_back();
    for (MissionId id : ids) routes.back().push_back(service.mission(id).route.edges);
  }
  EXPECT_EQ(routes[0], routes[1]);
  EXPECT_EQ(routes[0], routes[2]);
  DispatchConfig bad;
  bad.repair_threads = 0;
  EXPECT_THROW(DispatchService(grid(), bad, nullptr, 0.0), std::invalid_argument);
  for (int priority : {-1, 100}) {
    DispatchConfig bad_priority;
    bad_priority.repair_realtime_priority = priority;
    EXPECT_THROW(DispatchService(grid(), bad_priority, nullptr, 0.0), std::invalid_argument) << priority;
  }
}

// Half the I/O threads repair by default, at least one, and the service accepts every count the
// rule gives.
TEST(DispatchService, DefaultRepairThreadsAreHalfTheIoThreads) {
  EXPECT_EQ(default_repair_threads(1), 1);
  EXPECT_EQ(default_repair_threads(2), 1);
  EXPECT_EQ(default_repair_threads(3), 1);
  EXPECT_EQ(default_repair_threads(4), 2);
  EXPECT_EQ(default_repair_threads(64), 32);
  for (int io : {1, 2, 64}) {
    DispatchConfig config;
    config.repair_threads = default_repair_threads(io);
    EXPECT_NO_THROW(DispatchService(grid(), config, nullptr, 0.0)) << io;
  }
}

// The missions' graph changes how a repair works, not what it finds: a service on the turn graph
// and one on the shared hierarchy, given the same missions (two profiles at two top speeds: four
// cost models, of which the hierarchy holds at most three, so the fourth plans on the turn graph
// inside it), congestion, closures, expiries and positions, keep routes of the same cost after
// every step. The turn-graph planner is itself checked against Dijkstra (above, and in the
// planner's tests).
TEST(DispatchService, HierarchyAndTurnGraphKeepRoutesOfTheSameCost) {
  DispatchConfig flat_config;
  flat_config.planner_graph = PlannerGraph::turn_graph;
  DispatchConfig cch_config;
  cch_config.planner_graph = PlannerGraph::hierarchy;
  cch_config.max_hierarchy_models = 3;
  DispatchService flat(grid(), flat_config, nullptr, 0.0);
  DispatchService cch(grid(), cch_config, nullptr, 0.0);
  ASSERT_EQ(flat.planner_graph(), PlannerGraph::turn_graph);
  ASSERT_EQ(cch.planner_graph(), PlannerGraph::hierarchy);
  EXPECT_EQ(flat.hierarchy(), nullptr);
  ASSERT_NE(cch.hierarchy(), nullptr);

  const auto n = static_cast<std::uint32_t>(grid().node_count());
  std::mt19937 rng(17);
  std::vector<MissionId> ids;
  for (int i = 0; i < 6; ++i) {
    MissionRequest r = request("v-" + std::to_string(i));
    r.origin = node_ll(NodeId{static_cast<std::uint32_t>(rng() % n)});
    r.destination = node_ll(NodeId{static_cast<std::uint32_t>(rng() % n)});
    r.profile = i % 2 == 0 ? "ambulance" : "fire_engine";
    r.vmax_kmh = i < 4 ? 120.0 : 60.0;
    const MissionView a = flat.create_mission(r, 0.0);
    const MissionView b = cch.create_mission(r, 0.0);
    ASSERT_EQ(a.id, b.id);
    EXPECT_NEAR(a.route.travel_time_s, b.route.travel_time_s, 1e-6 * a.route.travel_time_s);
    ids.push_back(a.id);
  }
  // Ambulance and fire engine at 120 km/h, then the ambulance at 60 km/h; the fire engine at 60 km/h
  // finds no room.
  EXPECT_EQ(cch.hierarchy()->models_in_use(), 3u);

  const auto same_costs = [&](const std::string& when) {
    for (MissionId id : ids) {
      const MissionView a = flat.mission(id);
      const MissionView b = cch.mission(id);
      ASSERT_EQ(a.state, b.state) << when << ", mission " << id;
      if (a.state != MissionState::active) continue;
      ASSERT_EQ(a.route.found, b.route.found) << when << ", mission " << id;
      if (!a.route.found) continue;  // closed in: no route on either
      EXPECT_NEAR(a.route.travel_time_s, b.route.travel_time_s, 1e-6 * std::max(1.0, a.route.travel_time_s))
          << when << ", mission " << id;
    }
  };
  std::uniform_real_distribution<double> factor(0.5, 5.0);
  double now = 1.0;
  for (int step = 0; step < 40; ++step) {
    now += 3.0;
    std::vector<CongestionUpdate> batch;
    for (int j = 0; j < 12; ++j) {
      CongestionUpdate u;
      u.edge = EdgeId{static_cast<std::uint32_t>(rng() % grid().edge_count())};
      if (j == 0) {
        u.speed_kmh = 0.0;  // a closure
      } else {
        u.factor = factor(rng);
      }
      if (j % 3 == 0) u.expires_in_s = 10.0;
      batch.push_back(u);
    }
    const CongestionResult a = flat.report_congestion(batch, now);
    const CongestionResult b = cch.report_congestion(batch, now);
    EXPECT_EQ(a.missions_replanned, b.missions_replanned);
    EXPECT_EQ(a.customization_s, 0.0);
    EXPECT_GT(b.customization_s, 0.0);
    same_costs("after batch " + std::to_string(step));
    // Each vehicle moves half way along its route's second edge now and then.
    if (step % 4 == 1) {
      for (MissionId id : ids) {
        const MissionView m = flat.mission(id);
        if (m.state != MissionState::active || m.route.edges.size() < 3) continue;
        PositionReport p;
        p.vehicle_id = m.vehicle_id;
        const EdgeId e = m.route.edges[1];
        p.position = grid().projection().to_lat_lon(grid().point_along(e, grid().length_m(e) / 2));
        p.timestamp_s = now;
        (void)flat.report_position(p, now);
        (void)cch.report_position(p, now);
      }
      same_costs("after positions at batch " + std::to_string(step));
    }
    flat.tick(now);
    cch.tick(now);  // expiries: a change like any other
    same_costs("after the tick at batch " + std::to_string(step));
  }
  // A model lives as long as a mission uses it.
  for (MissionId id : {ids[4], ids[5]}) {
    if (cch.mission(id).state == MissionState::active) (void)cch.cancel_mission(id, now);
  }
  std::set<std::pair<std::string, double>> in_use;
  for (const MissionView& m : cch.missions(MissionState::active)) in_use.insert({m.profile, m.vmax_kmh});
  EXPECT_EQ(cch.hierarchy()->models_in_use(), in_use.size());
  EXPECT_FALSE(in_use.count({"ambulance", 60.0}) || in_use.count({"fire_engine", 60.0}));
}

// `automatic` takes the hierarchy where it came out sparse, and the turn graph where it did not.
TEST(DispatchService, AutomaticPlannerGraphKeepsTheTurnGraphWhereTheHierarchyIsDense) {
  DispatchService sparse(grid(), {}, nullptr, 0.0);
  ASSERT_EQ(sparse.planner_graph(), PlannerGraph::hierarchy);
  const double density = sparse.hierarchy()->density();
  EXPECT_GT(density, 1.0);
  EXPECT_LE(density, DispatchConfig{}.max_hierarchy_density);

  DispatchConfig strict;
  strict.max_hierarchy_density = density * 0.99;
  DispatchService dense(grid(), strict, nullptr, 0.0);
  EXPECT_EQ(dense.planner_graph(), PlannerGraph::turn_graph);
  EXPECT_EQ(dense.hierarchy(), nullptr);
  const MissionView m = dense.create_mission(request("amb-9"), 0.0);
  EXPECT_TRUE(m.route.found);
  // Asked for by name, the hierarchy is used whatever its density.
  strict.planner_graph = PlannerGraph::hierarchy;
  EXPECT_EQ(DispatchService(grid(), strict, nullptr, 0.0).planner_graph(), PlannerGraph::hierarchy);

  for (double bad : {0.0, -1.0, std::nan("")}) {
    DispatchConfig c;
    c.max_hierarchy_density = bad;
    EXPECT_THROW(DispatchService(grid(), c, nullptr, 0.0), std::invalid_argument) << bad;
  }
  DispatchConfig no_models;
  no_models.max_hierarchy_models = 0;
  EXPECT_THROW(DispatchService(grid(), no_models, nullptr, 0.0), std::invalid_argument);
}

}  // namespace
}  // namespace corridor::server
