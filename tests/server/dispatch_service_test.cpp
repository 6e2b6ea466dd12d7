// The dispatch service's requests one by one: missions, positions along a route, congestion and
// its expiry, and bad input answered with its status.
#include "server/dispatch_service.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <string>
#include <vector>

#include "maps/intersection_geometry.hpp"
#include "maps/osm_import.hpp"
#include "planner/one_to_one_search.hpp"
#include "preemption/signal_costs.hpp"
#include "tests/maps/osm_fixture.hpp"
#include "tests/server/dispatch_fixture.hpp"

namespace corridor::server {
namespace {

using testing::code_of;
using testing::corner;
using testing::grid;
using testing::node_ll;
using testing::request;

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
  p.source = "gps";
  // A timestamp from the far future would make every later report stale: refused, as is one before
  // the epoch. Up to max_clock_ahead_s (300 s) of skew is taken.
  p.timestamp_s = 1e300;
  EXPECT_EQ(code_of([&] { service.report_position(p, 100.0); }), 400);
  p.timestamp_s = 100.0 + 301.0;
  EXPECT_EQ(code_of([&] { service.report_position(p, 100.0); }), 400);
  p.timestamp_s = -1.0;
  EXPECT_EQ(code_of([&] { service.report_position(p, 100.0); }), 400);
  p.timestamp_s = 100.0 + 299.0;
  EXPECT_EQ(service.report_position(p, 100.0).match.disposition, "followed");
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

// A detector's standing queue on an approach the route takes (POST .../counts with queue_m) starts
// that light's hold earlier, early enough to clear the queue: vicinity-aware preemption in the
// server. A report out of range is refused whole.
TEST(DispatchService, ADetectorsQueueOnTheApproachStartsItsHoldEarlier) {
  DispatchConfig config;
  config.preemption.vicinity.enabled = true;
  DispatchService service(grid(), config, nullptr, 0.0);
  const MissionView m = service.create_mission(request("amb-q"), 0.0);
  // The last crossing: far enough ahead for an earlier start to show.
  ASSERT_FALSE(m.schedule.empty());
  const auto target = std::max_element(m.schedule.begin(), m.schedule.end(),
                                       [](const auto& a, const auto& b) { return a.arrival_s < b.arrival_s; });
  ASSERT_GT(target->arrival_s, 60.0);
  const NodeId node = target->node;
  const double before = target->start_s;
  CountsReport queue;
  const char side = target->movement_label.front();  // "N->S"
  queue.approach = side == 'N' ? maps::Compass::north : side == 'E' ? maps::Compass::east : side == 'S' ? maps::Compass::south
                                                                                                  : maps::Compass::west;
  queue.queue_m = 60.0;
  service.report_detectors(node, queue, 1.0);
  CountsReport bad = queue;
  bad.occupancy = 1.5;
  EXPECT_EQ(code_of([&] { service.report_detectors(node, bad, 1.0); }), 400);
  bad = queue;
  bad.queue_m = -3.0;
  EXPECT_EQ(code_of([&] { service.report_detectors(node, bad, 1.0); }), 400);
  EXPECT_EQ(code_of([&] { service.report_detectors(NodeId{static_cast<std::uint32_t>(grid().node_count() + 5)}, queue, 1.0); }), 404);
  // The next position report re-times the mission's signals with the queue.
  PositionReport p;
  p.vehicle_id = "amb-q";
  p.position = corner(false);
  p.timestamp_s = 2.0;
  service.report_position(p, 2.0);
  const auto after = service.mission(m.id).schedule;
  const auto it = std::find_if(after.begin(), after.end(), [&](const auto& e) { return e.node == node; });
  ASSERT_NE(it, after.end());
  EXPECT_EQ(it->vicinity, "approach_queue");
  // The queue's 8 vehicles take l1 + h·8 = 18 s to discharge, and the vehicle meets its tail first.
  EXPECT_LT(it->start_s, before - 15.0) << "before " << before << " s, after " << it->start_s << " s";
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

}  // namespace
}  // namespace corridor::server
