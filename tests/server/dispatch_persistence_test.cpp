// What the dispatch service stores survives a restart: active missions, their profiles, and the
// database's own versions.
#include "server/dispatch_service.hpp"

#include <gtest/gtest.h>
#include <sqlite3.h>

#include <string>
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
  EXPECT_EQ(store.schema_version(), 5);
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

// GET /v1/vehicles after a restart shows what it showed before: every vehicle that reported, with
// or without a mission, as it reported (source and speed included).
TEST(DispatchService, EveryVehiclesLatestPositionSurvivesARestart) {
  TempDb db;
  std::vector<VehicleView> before;
  {
    Store store(db.path());
    DispatchService service(grid(), {}, &store, 0.0);
    const MissionView m = service.create_mission(request("amb-a"), 0.0);
    PositionReport p;
    p.vehicle_id = "amb-a";
    p.position = grid().projection().to_lat_lon(grid().point_along(m.route.edges[1], 1.0));
    p.timestamp_s = 2.0;
    p.speed_mps = 9.5;
    service.report_position(p, 2.0).durable->wait();
    p.vehicle_id = "free-1";  // no mission
    p.position = corner(true);
    p.source = "vo";
    p.speed_mps = 12.0;
    p.heading_deg = 90.0;
    p.timestamp_s = 3.0;
    service.report_position(p, 3.0).durable->wait();
    before = service.vehicles();
  }
  ASSERT_EQ(before.size(), 2u);
  Store store(db.path());
  DispatchService service(grid(), {}, &store, 10.0);
  const std::vector<VehicleView> after = service.vehicles();
  ASSERT_EQ(after.size(), before.size());
  for (std::size_t i = 0; i < after.size(); ++i) {
    SCOPED_TRACE(after[i].vehicle_id);
    EXPECT_EQ(after[i].vehicle_id, before[i].vehicle_id);
    EXPECT_DOUBLE_EQ(after[i].position.lat_deg, before[i].position.lat_deg);
    EXPECT_DOUBLE_EQ(after[i].position.lon_deg, before[i].position.lon_deg);
    EXPECT_EQ(after[i].heading_deg, before[i].heading_deg);
    EXPECT_EQ(after[i].speed_mps, before[i].speed_mps);
    EXPECT_DOUBLE_EQ(after[i].timestamp_s, before[i].timestamp_s);
    EXPECT_EQ(after[i].source, before[i].source);
    EXPECT_EQ(after[i].mission, before[i].mission);
  }
  EXPECT_EQ(after[1].source, "vo");
  EXPECT_EQ(after[1].speed_mps, 12.0);
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
                         "ALTER TABLE missions DROP COLUMN profile; DROP TABLE signal_calls;"
                         "DELETE FROM schema_migrations WHERE version >= 2;",
                         nullptr, nullptr, nullptr),
            SQLITE_OK);
  sqlite3_close(raw);
  Store store(db.path());
  EXPECT_EQ(store.schema_version(), 5);
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
    EXPECT_EQ(store.schema_version(), 5);
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
