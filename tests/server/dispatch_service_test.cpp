#include "server/dispatch_service.hpp"

#include <pthread.h>
#include <sched.h>

#include <gtest/gtest.h>
#include <sqlite3.h>

#include <cmath>
#include <filesystem>
#include <atomic>
#include <map>
#include <numeric>
#include <random>
#include <set>
#include <thread>

#include "maps/intersection_geometry.hpp"
#include "maps/synthetic_grid.hpp"
#include "planner/one_to_one_search.hpp"
#include "preemption/signal_costs.hpp"
#include "maps/osm_import.hpp"
#include "tests/maps/osm_fixture.hpp"
#include "tests/server/temp_db.hpp"

namespace corridor::server {
namespace {

maps::RoadGraph test_grid() {
  maps::GridSpec spec;
  spec.rows = 10;
  spec.cols = 10;
  spec.seed = 21;
  spec.oneway_fraction = 0.0;
  spec.removal_fraction = 0.0;
  spec.signal_fraction = 0.5;
  return maps::make_perturbed_grid(spec);
}

const maps::RoadGraph& grid() {
  static const maps::RoadGraph g = test_grid();
  return g;
}

maps::LatLon node_ll(NodeId n) { return grid().projection().to_lat_lon(grid().position(n)); }
maps::LatLon corner(bool far) { return node_ll(NodeId{far ? static_cast<std::uint32_t>(grid().node_count() - 1) : 0u}); }

MissionRequest request(const std::string& vehicle) {
  MissionRequest r;
  r.vehicle_id = vehicle;
  r.origin = corner(false);
  r.destination = corner(true);
  r.priority = 2;
  return r;
}

int code_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const ApiError& e) {
    return e.status();
  }
  return 0;
}

TEST(DispatchService, CreatesAMissionWithRouteEtaAndPreemptionSchedule) {
  DispatchService service(grid(), {}, nullptr, 1000.0);
  std::vector<std::string> events;
  service.subscribe([&](const DispatchEvent& e) { events.push_back(e.kind); });
  const MissionView m = service.create_mission(request("amb-1"), 1000.0);
  EXPECT_EQ(m.state, MissionState::active);
  ASSERT_TRUE(m.route.found);
  EXPECT_GT(m.route.travel_time_s, 0.0);
  EXPECT_EQ(m.route_revision, 1u);
  EXPECT_FALSE(m.schedule.empty());  // half the junctions are signalized; a corner-to-corner route crosses some
  for (const auto& e : m.schedule) EXPECT_LE(e.start_s, e.arrival_s);
  EXPECT_EQ(events.front(), "mission_created");
  // The service's route is the optimal one (Dijkstra oracle with the same costs).
  planner::CostOverlay overlay(grid());
  overlay.set_signal_delay(grid(), DispatchConfig{}.signal_delay_s);
  // Lights with a plan cost their expected transition: the service preempts them.
  preemption::set_signal_costs(overlay, grid(), maps::default_signal_plans(grid()), preemption::SignalCostRule::preempted);
  const planner::TravelCost cost(grid(), overlay, {120.0 / 3.6});
  planner::OneToOneSearch dijkstra;
  const auto oracle = dijkstra.run(planner::SearchSpace(cost, {m.route.start}, {m.route.goal}), false);
  EXPECT_NEAR(oracle.travel_time_s, m.route.travel_time_s, 1e-6);
}

TEST(DispatchService, RejectsBadRequestsWithStatusCodes) {
  DispatchService service(grid(), {}, nullptr, 0.0);
  MissionRequest r = request("");
  EXPECT_EQ(code_of([&] { service.create_mission(r, 0.0); }), 400);
  r = request("v");
  r.vmax_kmh = 0.0;
  EXPECT_EQ(code_of([&] { service.create_mission(r, 0.0); }), 400);
  r = request("v");
  r.destination = {0.0, 0.0};
  EXPECT_EQ(code_of([&] { service.create_mission(r, 0.0); }), 422);
  r = request("v");
  r.origin.reset();  // no known position for this vehicle
  EXPECT_EQ(code_of([&] { service.create_mission(r, 0.0); }), 422);
  service.create_mission(request("v"), 0.0);
  EXPECT_EQ(code_of([&] { service.create_mission(request("v"), 0.0); }), 409);  // one active mission per vehicle
  EXPECT_EQ(code_of([&] { (void)service.mission(999); }), 404);
  EXPECT_EQ(code_of([&] { service.cancel_mission(999, 0.0); }), 404);
  PositionReport p;
  p.vehicle_id = "v";
  p.position = {std::nan(""), 9.5};
  EXPECT_EQ(code_of([&] { service.report_position(p, 0.0); }), 422);
  p.position = corner(false);
  p.source = "radar";
  EXPECT_EQ(code_of([&] { service.report_position(p, 0.0); }), 400);
  EXPECT_EQ(code_of([&] { service.report_congestion({}, 0.0); }), 400);
  CongestionUpdate u;
  u.edge = EdgeId{static_cast<std::uint32_t>(grid().edge_count() + 5)};
  u.factor = 2.0;
  EXPECT_EQ(code_of([&] { service.report_congestion({u}, 0.0); }), 422);
  u.edge = EdgeId{0};
  u.speed_kmh = 20.0;  // two values at once
  EXPECT_EQ(code_of([&] { service.report_congestion({u}, 0.0); }), 400);
}

// A 3 x 3 grid of two-way streets 100 m apart and, 60 m south of it, a street that joins nothing
// (a car park's): an ambulance there is dispatched from the grid's nearest street, and its position
// reports from the car park keep the mission going instead of ending it for want of a route.
TEST(DispatchService, AVehicleOnARoadCutOffFromTheRestGoesOnFromTheNearestStreetThatLeadsOn) {
  using maps::testing::at;
  const std::map<std::string, std::string> road{{"highway", "residential"}};
  std::vector<maps::testing::FixtureNode> nodes;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) nodes.push_back(at(1 + r * 3 + c, c * 100.0, r * 100.0));
  }
  nodes.push_back(at(30, 0, -60));
  nodes.push_back(at(31, 200, -60));
  std::vector<maps::testing::FixtureWay> ways;
  for (int r = 0; r < 3; ++r) ways.push_back({100 + r, {1 + r * 3LL, 2 + r * 3LL, 3 + r * 3LL}, road});
  for (int c = 0; c < 3; ++c) ways.push_back({200 + c, {1LL + c, 4LL + c, 7LL + c}, road});
  ways.push_back({400, {30, 31}, road});
  maps::testing::TempDir dir;
  maps::testing::write_osm(dir.path() / "car_park.osm", nodes, ways);
  maps::OsmImportOptions options;
  options.show_progress = false;
  const maps::RoadGraph g = maps::import_osm(dir.path() / "car_park.osm", options);
  ASSERT_EQ(g.main_component_nodes(), 9u);
  const auto ll = [](double x, double y) {
    const auto n = at(0, x, y);
    return maps::LatLon{n.lat, n.lon};
  };
  DispatchService service(g, {}, nullptr, 0.0);
  MissionRequest r = request("amb-car-park");
  r.origin = ll(100, -58);  // on the car park's street
  r.destination = ll(200, 200);
  const MissionView m = service.create_mission(r, 0.0);
  ASSERT_TRUE(m.route.found);
  EXPECT_TRUE(g.in_main_component(m.route.edges.front()));
  PositionReport p;
  p.vehicle_id = "amb-car-park";
  p.position = ll(120, -60);
  p.timestamp_s = 1.0;
  const PositionResult res = service.report_position(p, 1.0);
  EXPECT_FALSE(res.completed);
  const MissionView after = service.mission(m.id);
  EXPECT_EQ(after.state, MissionState::active);
  ASSERT_TRUE(after.route.found);
  EXPECT_TRUE(g.in_main_component(after.route.edges.front()));
}

// Drive the vehicle along its route with position reports: the start advances, signals behind it
// are released, and the mission completes at the destination.
TEST(DispatchService, PositionsAlongTheRouteCompleteTheMission) {
  DispatchService service(grid(), {}, nullptr, 0.0);
  std::vector<DispatchEvent> events;
  service.subscribe([&](const DispatchEvent& e) { events.push_back(e); });
  const MissionView m = service.create_mission(request("amb-2"), 0.0);
  double t = 0.0;
  bool completed = false;
  for (std::size_t i = 1; i + 1 < m.route.edges.size() && !completed; ++i) {
    const EdgeId e = m.route.edges[i];
    t += 10.0;
    PositionReport p;
    p.vehicle_id = "amb-2";
    p.position = grid().projection().to_lat_lon(grid().point_along(e, grid().length_m(e) / 2));
    p.timestamp_s = t;
    const PositionResult r = service.report_position(p, t);
    ASSERT_EQ(r.mission, m.id);
    EXPECT_FALSE(r.route_changed) << "driving the planned route must not change it";
    completed = r.completed;
    service.tick(t);
  }
  PositionReport last;
  last.vehicle_id = "amb-2";
  last.position = corner(true);
  last.timestamp_s = t + 10;  // an older report would be stale, and move nothing
  const PositionResult r = service.report_position(last, t + 10);
  EXPECT_TRUE(r.completed || completed);
  EXPECT_EQ(service.mission(m.id).state, MissionState::completed);
  EXPECT_EQ(service.active_mission_count(), 0u);
  EXPECT_TRUE(std::any_of(events.begin(), events.end(), [](const auto& e) { return e.kind == "mission_completed"; }));
  EXPECT_TRUE(std::any_of(events.begin(), events.end(), [](const auto& e) { return e.kind == "preemption_released"; }));
  // The finished mission still shows its final schedule.
  const auto finished = service.mission(m.id).schedule;
  EXPECT_FALSE(finished.empty());
  for (const auto& e : finished) EXPECT_NE(e.state, preemption::EntryState::active);
}

TEST(DispatchService, CongestionOnTheRouteChangesIt) {
  DispatchService service(grid(), {}, nullptr, 0.0);
  std::vector<DispatchEvent> events;
  service.subscribe([&](const DispatchEvent& e) { events.push_back(e); });
  const MissionView m = service.create_mission(request("amb-3"), 0.0);
  std::vector<CongestionUpdate> updates;
  for (std::size_t i = 1; i + 1 < m.route.edges.size(); ++i) {
    CongestionUpdate u;
    u.edge = m.route.edges[i];
    u.speed_kmh = 3.0;
    u.expires_in_s = 120.0;
    updates.push_back(u);
  }
  const CongestionResult r = service.report_congestion(updates, 5.0);
  EXPECT_EQ(r.missions_replanned, 1u);
  EXPECT_EQ(r.routes_changed, 1u);
  const MissionView after = service.mission(m.id);
  EXPECT_NE(after.route.edges, m.route.edges);
  EXPECT_EQ(after.route_revision, 2u);
  EXPECT_TRUE(std::any_of(events.begin(), events.end(),
                          [](const auto& e) { return e.kind == "route_changed" && e.reason == "congestion"; }));
  // When the congestion expires, the original route comes back.
  service.tick(200.0);
  EXPECT_EQ(service.mission(m.id).route.edges, m.route.edges);
}

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
    ASSERT_EQ(r.mission_replan_s.size(), r.missions_replanned);
    EXPECT_EQ(*std::max_element(r.mission_replan_s.begin(), r.mission_replan_s.end()), r.slowest_replan_s);
    // The same repairs in CPU time: one per repair, each spent, and none beyond its wall time (the
    // wall window encloses the CPU clock's reads; the thread clock's 1 µs grain gets a margin).
    ASSERT_EQ(r.mission_replan_cpu_s.size(), r.missions_replanned);
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

// An expiry ends only the update it came with: a later closure without expiry stays in force.
TEST(DispatchService, OldExpiryDoesNotReopenALaterClosure) {
  DispatchService service(grid(), {}, nullptr, 0.0);
  const MissionView m = service.create_mission(request("amb-4"), 0.0);
  const EdgeId e = m.route.edges[m.route.edges.size() / 2];
  CongestionUpdate slow;
  slow.edge = e;
  slow.factor = 3.0;
  slow.expires_in_s = 60.0;
  service.report_congestion({slow}, 1.0);
  CongestionUpdate closed;
  closed.edge = e;
  closed.speed_kmh = 0.0;  // closed until further notice
  service.report_congestion({closed}, 2.0);
  auto uses = [&](EdgeId x) {
    const auto edges = service.mission(m.id).route.edges;
    return std::count(edges.begin(), edges.end(), x);
  };
  EXPECT_EQ(uses(e), 0);
  service.tick(100.0);  // the first update's expiry passes
  EXPECT_EQ(uses(e), 0);
  // And the reverse order: a later update with an earlier expiry ends at its own time.
  CongestionUpdate brief = slow;
  brief.expires_in_s = 10.0;
  service.report_congestion({brief}, 101.0);
  service.tick(120.0);
  EXPECT_EQ(service.mission(m.id).route.edges, m.route.edges);
}

TEST(DispatchService, OsmWayUpdatesAndClosuresApplyToEveryEdgeOfTheWay) {
  DispatchService service(grid(), {}, nullptr, 0.0);
  CongestionUpdate u;
  u.osm_way_id = grid().osm_way(EdgeId{3}).v;
  u.speed_kmh = 0.0;  // closed
  EXPECT_EQ(service.report_congestion({u}, 0.0).edges_changed, grid().twin(EdgeId{3}).valid() ? 2u : 1u);
  u.osm_way_id = 987654321;
  EXPECT_EQ(code_of([&] { service.report_congestion({u}, 0.0); }), 422);
}

TEST(DispatchService, PersistsAndResumesActiveMissionsAfterRestart) {
  TempDb db;
  MissionId kept = 0, cancelled = 0;
  std::vector<EdgeId> congested;
  {
    Store store(db.path());
    DispatchService service(grid(), {}, &store, 0.0);
    kept = service.create_mission(request("amb-a"), 0.0).id;
    cancelled = service.create_mission(request("amb-b"), 0.0).id;
    service.cancel_mission(cancelled, 1.0);
    const MissionView m = service.mission(kept);
    const EdgeId e = m.route.edges[m.route.edges.size() / 2];
    PositionReport p;
    p.vehicle_id = "amb-a";
    p.position = grid().projection().to_lat_lon(grid().point_along(e, 1.0));
    service.report_position(p, 2.0);
    CongestionUpdate u;
    u.edge = m.route.edges.back();
    u.factor = 7.0;
    service.report_congestion({u}, 3.0);
    congested.push_back(m.route.edges.back());
    EXPECT_EQ(store.count("missions"), 2u);
    EXPECT_EQ(store.count("positions"), 1u);
    EXPECT_GE(store.count("route_revisions"), 2u);
    EXPECT_EQ(store.count("congestion"), 1u);
    EXPECT_GT(store.count("preemption_events"), 0u);
  }  // the process "dies" here: nothing is flushed beyond what each call committed
  Store store(db.path());
  EXPECT_EQ(store.schema_version(), 4);
  DispatchService service(grid(), {}, &store, 10.0);
  EXPECT_EQ(service.active_mission_count(), 1u);
  const MissionView resumed = service.mission(kept);
  EXPECT_EQ(resumed.state, MissionState::active);
  EXPECT_EQ(resumed.vehicle_id, "amb-a");
  // It resumes from the last position, not from the origin.
  ASSERT_TRUE(resumed.last_position.has_value());
  EXPECT_NE(resumed.last_position->lat_deg, request("x").origin->lat_deg);
  EXPECT_EQ(service.mission(cancelled).state, MissionState::cancelled);
  EXPECT_EQ(code_of([&] { service.create_mission(request("amb-a"), 10.0); }), 409);
  // New missions are numbered after every stored one.
  EXPECT_EQ(service.create_mission(request("amb-c"), 10.0).id, std::max(kept, cancelled) + 1);
  EXPECT_EQ(store.count("missions"), 3u);
  // Congestion still in force applies to the resumed planner.
  planner::CostOverlay overlay(grid());
  overlay.set_signal_delay(grid(), DispatchConfig{}.signal_delay_s);
  // Lights with a plan cost their expected transition: the service preempts them.
  preemption::set_signal_costs(overlay, grid(), maps::default_signal_plans(grid()), preemption::SignalCostRule::preempted);
  overlay.set_edge(congested[0], {7.0, 0.0});
  const planner::TravelCost cost(grid(), overlay, {120.0 / 3.6});
  planner::OneToOneSearch dijkstra;
  const auto oracle = dijkstra.run(planner::SearchSpace(cost, {resumed.route.start}, {resumed.route.goal}), false);
  EXPECT_NEAR(oracle.travel_time_s, resumed.route.travel_time_s, 1e-6);
}

TEST(Store, MigratesVersion1PositionsToEachVehiclesLatest) {
  TempDb db;
  PositionReport p;
  p.vehicle_id = "amb-a";
  {
    Store store(db.path());
    MissionRow m;
    m.id = 7;
    m.vehicle_id = "amb-a";
    m.destination = {43.74, 7.43};
    store.insert_mission(m);
    for (int i = 0; i < 3; ++i) {
      p.position = {43.73 + 0.001 * i, 7.42};
      p.timestamp_s = i;
      store.insert_position(p, std::nullopt, i);
    }
    p.vehicle_id = "amb-b";
    p.position = {43.70, 7.40};
    store.insert_position(p, std::nullopt, 5.0);
  }
  // Back to the version-1 layout: the per-vehicle index, no table of latest positions.
  sqlite3* raw = nullptr;
  ASSERT_EQ(sqlite3_open(db.path().c_str(), &raw), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(raw,
                         "DROP TABLE vehicle_last_position; CREATE INDEX positions_vehicle ON positions(vehicle_id, id);"
                         "ALTER TABLE positions DROP COLUMN disposition; ALTER TABLE positions DROP COLUMN edge;"
                         "ALTER TABLE positions DROP COLUMN offset_m; ALTER TABLE positions DROP COLUMN match_confidence;"
                         "ALTER TABLE missions DROP COLUMN profile;"
                         "DELETE FROM schema_migrations WHERE version >= 2;",
                         nullptr, nullptr, nullptr),
            SQLITE_OK);
  sqlite3_close(raw);
  Store store(db.path());
  EXPECT_EQ(store.schema_version(), 4);
  const auto a = store.last_position("amb-a");
  ASSERT_TRUE(a.has_value());
  EXPECT_DOUBLE_EQ(a->position.lat_deg, 43.732);
  EXPECT_DOUBLE_EQ(a->timestamp_s, 2.0);
  ASSERT_TRUE(store.last_position("amb-b").has_value());
  EXPECT_DOUBLE_EQ(store.last_position("amb-b")->position.lat_deg, 43.70);
  EXPECT_FALSE(store.last_position("amb-c").has_value());
  // Later positions keep it current.
  p.vehicle_id = "amb-b";
  p.position = {43.71, 7.41};
  store.insert_position(p, std::nullopt, 6.0);
  EXPECT_DOUBLE_EQ(store.last_position("amb-b")->position.lat_deg, 43.71);
  EXPECT_EQ(store.count("positions"), 5u);
  // The mission stored before profiles existed is an ambulance's.
  ASSERT_EQ(store.missions(std::nullopt).size(), 1u);
  EXPECT_EQ(store.missions(std::nullopt).front().profile, "ambulance");
}

// A fire engine's mission plans with the fire engine's profile (a 3.5 m, 15 t truck that the
// ambulance's turn costs and limits do not describe), and keeps it across a restart. Missions
// stored before profiles existed (schema v3) resume as ambulances.
TEST(DispatchService, MissionKeepsItsVehicleProfileAcrossARestart) {
  TempDb db;
  MissionId fire = 0;
  {
    Store store(db.path());
    DispatchService service(grid(), {}, &store, 0.0);
    MissionRequest r = request("engine-1");
    r.profile = "fire_engine";
    r.vmax_kmh = 80.0;
    const MissionView m = service.create_mission(r, 0.0);
    fire = m.id;
    EXPECT_EQ(m.profile, "fire_engine");
    (void)service.create_mission(request("amb-1"), 0.0);
    // The route is the fire engine's: Dijkstra with that profile gives the same cost.
    planner::CostOverlay overlay(grid());
    overlay.set_signal_delay(grid(), DispatchConfig{}.signal_delay_s);
    preemption::set_signal_costs(overlay, grid(), maps::default_signal_plans(grid()), preemption::SignalCostRule::preempted);
    planner::VehicleProfile p = planner::fire_engine_profile();
    p.vmax_mps = 80.0 / 3.6;
    const planner::TravelCost cost(grid(), overlay, p);
    planner::OneToOneSearch dijkstra;
    const auto oracle = dijkstra.run(planner::SearchSpace(cost, {m.route.start}, {m.route.goal}), false);
    EXPECT_NEAR(oracle.travel_time_s, m.route.travel_time_s, 1e-6);
  }
  {
    Store store(db.path());
    DispatchService service(grid(), {}, &store, 10.0);
    EXPECT_EQ(service.mission(fire).profile, "fire_engine");
    EXPECT_EQ(service.mission(fire).vmax_kmh, 80.0);
  }
}

TEST(Store, RefusesADatabaseFromANewerBuild) {
  TempDb db;
  { Store store(db.path()); }
  {
    Store store(db.path());  // reopening an up-to-date database is fine
    EXPECT_EQ(store.schema_version(), 4);
  }
  sqlite3* raw = nullptr;
  ASSERT_EQ(sqlite3_open(db.path().c_str(), &raw), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(raw, "INSERT INTO schema_migrations(version, applied_s) VALUES (99, 0)", nullptr, nullptr, nullptr),
            SQLITE_OK);
  sqlite3_close(raw);
  try {
    Store store(db.path());
    FAIL() << "expected StoreError";
  } catch (const StoreError& e) {
    EXPECT_NE(std::string(e.what()).find("newer than this build"), std::string::npos) << e.what();
  }
  EXPECT_THROW(Store("/nonexistent-dir/x.db"), StoreError);
}

}  // namespace
}  // namespace corridor::server
