#include "server/dispatch_service.hpp"

#include <gtest/gtest.h>
#include <sqlite3.h>

#include <filesystem>
#include <random>

#include "maps/synthetic_grid.hpp"
#include "planner/one_to_one_search.hpp"
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
  EXPECT_EQ(store.schema_version(), 1);
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
  overlay.set_edge(congested[0], {7.0, 0.0});
  const planner::TravelCost cost(grid(), overlay, {120.0 / 3.6});
  planner::OneToOneSearch dijkstra;
  const auto oracle = dijkstra.run(planner::SearchSpace(cost, {resumed.route.start}, {resumed.route.goal}), false);
  EXPECT_NEAR(oracle.travel_time_s, resumed.route.travel_time_s, 1e-6);
}

TEST(Store, RefusesADatabaseFromANewerBuild) {
  TempDb db;
  { Store store(db.path()); }
  {
    Store store(db.path());  // reopening an up-to-date database is fine
    EXPECT_EQ(store.schema_version(), 1);
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
