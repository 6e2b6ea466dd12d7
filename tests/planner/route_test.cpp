#include "planner/route.hpp"

#include <gtest/gtest.h>

#include "maps/osm_import.hpp"
#include "planner/route_geojson.hpp"
#include "planner/snap_points.hpp"
#include "planner/one_to_one_search.hpp"
#include "planner/search_space.hpp"
#include "tests/planner/test_graphs.hpp"

#include <algorithm>
#include <queue>
#include <random>
#include "tests/maps/osm_fixture.hpp"
#include "tests/planner/test_graphs_line.hpp"

namespace corridor::planner {
namespace {

using testing::diamond;
using testing::edge_from_to;

TEST(Route, ArrivalTimesAndCostToGoalAlongTheRoute) {
  const auto g = diamond();
  CostOverlay overlay(g);
  overlay.set_node_delay(NodeId{g.head(edge_from_to(g, 1, 4))}, 4.0);  // D
  const TravelCost cost(g, overlay, testing::free_turns(30.0));
  const EdgeId ba = edge_from_to(g, 2, 1), ad = edge_from_to(g, 1, 4), dc = edge_from_to(g, 4, 3);
  const Route r = make_route(cost, {ba, 40.0}, {ba, ad, dc}, {dc, g.length_m(dc) / 2});
  ASSERT_TRUE(r.found);
  ASSERT_EQ(r.nodes.size(), 2u);
  const double ad_s = g.length_m(ad) / 20.0;
  EXPECT_DOUBLE_EQ(r.arrival_s[0], 6.0);                 // 60 m of B->A at 10 m/s, then at A
  EXPECT_NEAR(r.arrival_s[1], 6.0 + ad_s, 1e-12);        // at D, before its 4 s delay
  EXPECT_NEAR(r.travel_time_s, 6.0 + ad_s + 4.0 + ad_s / 2, 1e-12);
  EXPECT_NEAR(*r.cost_to_goal_s(r.nodes[1]), 4.0 + ad_s / 2, 1e-12);
  EXPECT_FALSE(r.cost_to_goal_s(NodeId{g.head(edge_from_to(g, 1, 2))}).has_value());  // B is not crossed
  EXPECT_NEAR(r.length_m, 60.0 + g.length_m(ad) * 1.5, 1e-9);
}

TEST(Route, PolylineIsClippedAtStartAndGoal) {
  const auto g = diamond();
  const CostOverlay overlay(g);
  const TravelCost cost(g, overlay, {30.0});
  const EdgeId ab = edge_from_to(g, 1, 2), bc = edge_from_to(g, 2, 3);
  const Route r = make_route(cost, {ab, 25.0}, {ab, bc}, {bc, 40.0});
  const auto line = route_polyline(g, r);
  ASSERT_EQ(line.size(), 3u);  // start point, B, goal point
  EXPECT_NEAR(line.front().x_m, 25.0, 1e-9);
  EXPECT_NEAR(line[1].x_m, 100.0, 1e-9);
  EXPECT_NEAR(line.back().x_m, 140.0, 1e-9);
}

TEST(Route, GeoJsonFeatureIsLonLatWithProperties) {
  const auto g = diamond();
  CostOverlay overlay(g);
  overlay.set_signal_delay(g, 5.0);
  const TravelCost cost(g, overlay, {30.0});
  const EdgeId ab = edge_from_to(g, 1, 2), bc = edge_from_to(g, 2, 3);
  const Route r = make_route(cost, {ab, 0.0}, {ab, bc}, {bc, 100.0});
  const auto f = route_to_geojson(g, r, "astar");
  EXPECT_EQ(f["type"], "Feature");
  EXPECT_EQ(f["geometry"]["type"], "LineString");
  const auto& first = f["geometry"]["coordinates"][0];
  EXPECT_NEAR(first[0].get<double>(), 9.5, 1e-3);  // lon first
  EXPECT_NEAR(first[1].get<double>(), 47.0, 1e-3);
  EXPECT_DOUBLE_EQ(f["properties"]["travel_time_s"].get<double>(), 25.0);
  EXPECT_DOUBLE_EQ(f["properties"]["length_m"].get<double>(), 200.0);
  EXPECT_EQ(f["properties"]["algorithm"], "astar");
  EXPECT_EQ(f["properties"]["nodes"].size(), 1u);
  EXPECT_EQ(f["properties"]["signals"].size(), 1u);
}

// A coordinate exactly on node B: as a goal it is the end of every edge arriving at B, as a start
// the beginning of every edge leaving it, so no zero-length piece is listed and no exit is missing;
// mid-edge, both directions stay.
TEST(SnapPoints, NodeCoordinatesOfferEveryEdgeAtTheNode) {
  const auto g = diamond();
  const EdgeId ab = edge_from_to(g, 1, 2), ba = edge_from_to(g, 2, 1);
  const EdgeId bc = edge_from_to(g, 2, 3), cb = edge_from_to(g, 3, 2);
  maps::SnapResult at_b;
  at_b.edge = ab;
  at_b.offset_m = 100.0;
  at_b.twin = ba;
  at_b.twin_offset_m = 0.0;
  auto edges_of = [](const std::vector<EdgePoint>& pts) {
    std::vector<EdgeId> out;
    for (const auto& p : pts) out.push_back(p.edge);
    std::sort(out.begin(), out.end());
    return out;
  };
  auto sorted = [](std::vector<EdgeId> v) {
    std::sort(v.begin(), v.end());
    return v;
  };
  const auto goal = points_from_snap(g, at_b, PointRole::goal);
  EXPECT_EQ(edges_of(goal), sorted({ab, cb}));
  for (const auto& p : goal) EXPECT_DOUBLE_EQ(p.offset_m, g.length_m(p.edge));
  const auto start = points_from_snap(g, at_b, PointRole::start);
  EXPECT_EQ(edges_of(start), sorted({ba, bc}));
  for (const auto& p : start) EXPECT_DOUBLE_EQ(p.offset_m, 0.0);
  // Within kAtNodeM of the node is at the node; farther is mid-edge.
  maps::SnapResult near_b = at_b;
  near_b.offset_m = 100.0 - kAtNodeM / 2;
  near_b.twin_offset_m = kAtNodeM / 2;
  EXPECT_EQ(node_at_snap(g, near_b), g.head(ab));
  maps::SnapResult mid = at_b;
  mid.offset_m = 40.0;
  mid.twin_offset_m = 60.0;
  EXPECT_FALSE(node_at_snap(g, mid).valid());
  EXPECT_EQ(points_from_snap(g, mid, PointRole::goal).size(), 2u);
  EXPECT_EQ(points_from_snap(g, mid, PointRole::start).size(), 2u);
}

// The detour the nearest-segment snap made: from a junction, a route must cost exactly the
// node-to-node shortest path, whichever edge of the junction the snap returned. Oracle: Dijkstra
// from the start node over graph edges, on random grids with one-way streets. With free turns (no
// turn cost, U-turns anywhere) the edge-based search graph must give exactly these node-to-node
// costs, which also checks the edge-based graph against the node-based one.
TEST(SnapPoints, RoutesBetweenJunctionsCostTheNodeToNodeShortestPath) {
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    const auto g = testing::random_grid(seed, 8, 8);
    const CostOverlay overlay(g);
    const TravelCost cost(g, overlay, testing::free_turns(30.0));
    std::mt19937_64 rng(seed);
    for (int trial = 0; trial < 20; ++trial) {
      const EdgeId se{std::uniform_int_distribution<std::uint32_t>(0, static_cast<std::uint32_t>(g.edge_count() - 1))(rng)};
      const EdgeId te{std::uniform_int_distribution<std::uint32_t>(0, static_cast<std::uint32_t>(g.edge_count() - 1))(rng)};
      // Snap results at the head of se and at the tail of te: the edge each names is arbitrary.
      maps::SnapResult s;
      s.edge = se;
      s.offset_m = g.length_m(se);
      s.twin = g.twin(se);
      s.twin_offset_m = 0.0;
      maps::SnapResult t;
      t.edge = te;
      t.offset_m = 0.0;
      t.twin = g.twin(te);
      t.twin_offset_m = t.twin.valid() ? g.length_m(t.twin) : 0.0;
      const NodeId from = g.head(se), to = g.tail(te);
      if (from == to) continue;
      // Node-to-node Dijkstra over transit_s, without the start node's own delay (the vehicle is
      // already there) and with the goal node's delay excluded (it stops on arrival).
      std::vector<double> dist(g.node_count(), kInfCost);
      using Item = std::pair<double, std::uint32_t>;
      std::priority_queue<Item, std::vector<Item>, std::greater<>> pq;
      dist[from.index()] = 0.0;
      pq.push({0.0, from.v});
      while (!pq.empty()) {
        const auto [d, u] = pq.top();
        pq.pop();
        if (d > dist[u]) continue;
        for (EdgeId e : g.out_edges(NodeId{u})) {
          const double w = NodeId{u} == from ? cost.edge_time_s(e) : cost.transit_s(e);
          const double nd = d + w;
          if (nd < dist[g.head(e).index()]) {
            dist[g.head(e).index()] = nd;
            pq.push({nd, g.head(e).v});
          }
        }
      }
      const SearchSpace space(cost, points_from_snap(g, s, PointRole::start), points_from_snap(g, t, PointRole::goal));
      OneToOneSearch search;
      const Route r = search.run(space, false);
      if (dist[to.index()] >= kInfCost) {
        EXPECT_FALSE(r.found);
        continue;
      }
      ASSERT_TRUE(r.found);
      EXPECT_NEAR(r.travel_time_s, dist[to.index()], 1e-6) << "seed " << seed << " trial " << trial;
      EXPECT_EQ(g.tail(r.edges.front()), from);
      EXPECT_EQ(g.head(r.edges.back()), to);
    }
  }
}

// A click at a junction and a second click there: the vehicle is already where it is sent. Goal
// points at the node's in-edges would make a start that leaves by an out-edge drive out and back:
// at a dead end, to the far dead end to turn (the loop `corridor route` gave before at_same_node).
TEST(SnapPoints, FromANodeToItselfIsAnEmptyRoute) {
  using maps::testing::at;
  const std::map<std::string, std::string> road{{"highway", "residential"}};
  // A street 1-2-3 with a side street 2-4: 1, 3 and 4 are dead ends, 2 a junction.
  maps::testing::TempDir dir;
  maps::testing::write_osm(dir.path() / "t.osm", {at(1, 0, 0), at(2, 100, 0), at(3, 200, 0), at(4, 100, 100)},
                           {{10, {1, 2, 3}, road}, {11, {2, 4}, road}});
  maps::OsmImportOptions options;
  options.show_progress = false;
  const auto g = maps::import_osm(dir.path() / "t.osm", options);
  const CostOverlay overlay(g);
  const TravelCost cost(g, overlay, VehicleProfile{});
  const maps::EdgeSnapper snapper(g);
  for (NodeId n : g.nodes()) {
    const maps::SnapResult s = snapper.snap(g.projection().to_lat_lon(g.position(n)));
    const maps::SnapResult t = s;
    ASSERT_TRUE(at_same_node(g, s, t));
    const auto starts = points_from_snap(g, s, PointRole::start);
    const auto goals = at_same_node(g, s, t) ? starts : points_from_snap(g, t, PointRole::goal);
    const Route r = OneToOneSearch().run(SearchSpace(cost, starts, goals), false);
    ASSERT_TRUE(r.found) << "node " << g.osm_node(n).v;
    EXPECT_EQ(r.length_m, 0.0) << "node " << g.osm_node(n).v;
    EXPECT_EQ(r.travel_time_s, 0.0) << "node " << g.osm_node(n).v;
  }
  // Two different nodes are not one place.
  const maps::SnapResult at1 = snapper.snap(g.projection().to_lat_lon(g.position(NodeId{0})));
  const NodeId last{static_cast<std::uint32_t>(g.node_count() - 1)};
  const maps::SnapResult at_last = snapper.snap(g.projection().to_lat_lon(g.position(last)));
  EXPECT_FALSE(at_same_node(g, at1, at_last));
}

// A ferry between two banks, and a long bridge round by the north. The ferry's duration (2 min for
// its 200 m, two pieces) is its whole crossing time; a profile that does not board ferries takes
// the bridge; the steps say where the vehicle rides.
TEST(Ferries, TheDurationIsTheCrossingTimeAndAProfileMayRefuseThem) {
  using maps::testing::at;
  const std::map<std::string, std::string> road{{"highway", "residential"}, {"name", "Bank"}};
  maps::testing::TempDir dir;
  maps::testing::write_osm(dir.path() / "f.osm",
                           {at(1, 0, 0), at(2, 100, 0), at(5, 200, 0), at(3, 300, 0), at(4, 400, 0), at(6, 0, 2000),
                            at(7, 400, 2000)},
                           {{10, {1, 2}, road},
                            {11, {3, 4}, road},
                            {12, {2, 5, 3}, {{"route", "ferry"}, {"duration", "0:02"}, {"name", "Ferry"}}},
                            {13, {1, 6, 7, 4}, {{"highway", "residential"}, {"name", "Bridge"}}}});
  maps::OsmImportOptions options;
  options.show_progress = false;
  const auto g = maps::import_osm(dir.path() / "f.osm", options);
  const CostOverlay overlay(g);
  auto node = [&](long long osm) {
    for (NodeId n : g.nodes()) {
      if (g.osm_node(n).v == osm) return n;
    }
    ADD_FAILURE() << "no node " << osm;
    return NodeId{};
  };
  auto trip = [&](const VehicleProfile& p) {
    const TravelCost cost(g, overlay, p);
    std::vector<EdgePoint> starts, goals;
    for (EdgeId e : g.out_edges(node(1))) starts.push_back({e, 0.0});
    for (EdgeId e : g.in_edges(node(4))) goals.push_back({e, g.length_m(e)});
    return OneToOneSearch().run(SearchSpace(cost, starts, goals), false);
  };
  const Route by_ferry = trip(VehicleProfile{});
  ASSERT_TRUE(by_ferry.found);
  double on_ferry_s = 0.0;
  for (std::size_t i = 0; i < by_ferry.edges.size(); ++i) {
    if (g.road_class(by_ferry.edges[i]) != maps::RoadClass::ferry) continue;
    on_ferry_s += by_ferry.arrival_s[i] - (i == 0 ? 0.0 : by_ferry.arrival_s[i - 1]);
  }
  EXPECT_NEAR(on_ferry_s, 120.0, 0.01);  // both pieces, turn costs aside (the ferry runs straight)
  const nlohmann::json steps = steps_to_json(g, by_ferry);
  std::vector<std::string> modes;
  for (const auto& s : steps) modes.push_back(s["name"].get<std::string>() + ":" + s["mode"].get<std::string>());
  EXPECT_EQ(modes, (std::vector<std::string>{"Bank:driving", "Ferry:ferry", "Bank:driving", "Bank:driving"}));

  VehicleProfile landlubber;
  landlubber.ferries = false;
  const Route by_bridge = trip(landlubber);
  ASSERT_TRUE(by_bridge.found);
  for (EdgeId e : by_bridge.edges) EXPECT_NE(g.road_class(e), maps::RoadClass::ferry);
  EXPECT_GT(by_bridge.travel_time_s, by_ferry.travel_time_s);
}

// Roads cut off from the main component (maps keeps them): a route onto a one-way spur that
// leaves the network is planned as clicked; a start where no road leads on, or on an island,
// gets its second try from the main component's nearest road; and where no component stands out
// (two separate streets of equal size) the nearest road wins and there is no route between them.
class CutOffRoads : public ::testing::Test {
 protected:
  static maps::RoadGraph import(const std::vector<maps::testing::FixtureNode>& nodes,
                                const std::vector<maps::testing::FixtureWay>& ways) {
    maps::testing::TempDir dir;
    maps::testing::write_osm(dir.path() / "cut_off.osm", nodes, ways);
    maps::OsmImportOptions options;
    options.show_progress = false;
    return maps::import_osm(dir.path() / "cut_off.osm", options);
  }
  // Plans with OneToOneSearch between the two clicks (x, y in metres), as `corridor route` does.
  static bool plan(const maps::RoadGraph& g, const maps::EdgeSnapper& snapper, maps::Point2 a, maps::Point2 b,
                   maps::SnapResult& from, maps::SnapResult& to) {
    const CostOverlay overlay(g);
    const TravelCost cost(g, overlay, VehicleProfile{});
    const maps::LatLon pa = g.projection().to_lat_lon(a), pb = g.projection().to_lat_lon(b);
    from = snapper.snap(pa);
    to = snapper.snap(pb);
    return plan_nearest_or_main(snapper, g, pa, from, pb, to, {}, [&](const maps::SnapResult& s, const maps::SnapResult& t) {
      OneToOneSearch search;
      const auto starts = points_from_snap(g, s, PointRole::start);
      return search.run(SearchSpace(cost, starts, at_same_node(g, s, t) ? starts : points_from_snap(g, t, PointRole::goal)), false)
          .found;
    });
  }
  static maps::Point2 at(const maps::RoadGraph& g, double x_m, double y_m) {
    const auto p = maps::testing::at(0, x_m, y_m);
    return g.projection().to_local({p.lat, p.lon});
  }
};

TEST_F(CutOffRoads, OnlyWhatNoRouteJoinsMovesToTheMainComponent) {
  using maps::testing::FixtureNode;
  const std::map<std::string, std::string> road{{"highway", "residential"}};
  const std::map<std::string, std::string> one_way{{"highway", "residential"}, {"oneway", "yes"}};
  // The main component: a two-way 3 x 3 grid, 100 m apart (nodes 1-9, 1 at the origin). A one-way
  // spur from node 3 (200, 0) east to 20, where no road leads on; an island 30-31 along y = -60.
  std::vector<FixtureNode> nodes;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) nodes.push_back(maps::testing::at(1 + r * 3 + c, c * 100.0, r * 100.0));
  }
  nodes.push_back(maps::testing::at(20, 300, 0));
  nodes.push_back(maps::testing::at(30, 0, -60));
  nodes.push_back(maps::testing::at(31, 200, -60));
  std::vector<maps::testing::FixtureWay> ways;
  for (int r = 0; r < 3; ++r) ways.push_back({100 + r, {1 + r * 3LL, 2 + r * 3LL, 3 + r * 3LL}, road});
  for (int c = 0; c < 3; ++c) ways.push_back({200 + c, {1LL + c, 4LL + c, 7LL + c}, road});
  ways.push_back({300, {3, 20}, one_way});
  ways.push_back({400, {30, 31}, road});
  const maps::RoadGraph g = import(nodes, ways);
  ASSERT_EQ(g.main_component_nodes(), 9u);
  const maps::EdgeSnapper snapper(g);
  maps::SnapResult from, to;

  // Onto the spur's end: a route exists, so the goal stays on the spur.
  ASSERT_TRUE(plan(g, snapper, at(g, 100, 200), at(g, 300, 0), from, to));
  EXPECT_FALSE(g.in_main_component(to.edge));
  EXPECT_NEAR(to.distance_m, 0.0, 0.5);
  // From it: nothing leads on, so the start moves to the main component's nearest road (node 3).
  ASSERT_TRUE(plan(g, snapper, at(g, 300, 0), at(g, 0, 200), from, to));
  EXPECT_TRUE(g.in_main_component(from.edge));
  EXPECT_NEAR(from.distance_m, 100.0, 0.5);
  // From the island, 10 m off it and 50 m off the grid's bottom row: the row.
  ASSERT_TRUE(plan(g, snapper, at(g, 100, -50), at(g, 0, 200), from, to));
  EXPECT_TRUE(g.in_main_component(from.edge));
  EXPECT_NEAR(from.distance_m, 50.0, 0.5);
  // From the island onto the spur's end: only the start moves; the spur is reachable as clicked.
  ASSERT_TRUE(plan(g, snapper, at(g, 100, -50), at(g, 300, 0), from, to));
  EXPECT_TRUE(g.in_main_component(from.edge));
  EXPECT_FALSE(g.in_main_component(to.edge));
  EXPECT_NEAR(to.distance_m, 0.0, 0.5);
  // Along the island itself: planned there.
  ASSERT_TRUE(plan(g, snapper, at(g, 20, -55), at(g, 180, -55), from, to));
  EXPECT_FALSE(g.in_main_component(from.edge));
  EXPECT_FALSE(g.in_main_component(to.edge));
  // No road of the main component within reach: no second snap.
  const maps::LatLon click = g.projection().to_lat_lon(at(g, 100, -50));
  const maps::SnapResult island = snapper.snap(click);
  EXPECT_FALSE(main_component_snap(snapper, g, click, island, {.max_distance_m = 40.0}).has_value());
  ASSERT_TRUE(main_component_snap(snapper, g, click, island, {}).has_value());
  // Main-only snapping passes the nearer island road by.
  EXPECT_FALSE(g.in_main_component(snapper.snap(click).edge));
  EXPECT_TRUE(g.in_main_component(snapper.snap(click, {.main_component_only = true}).edge));
}

TEST_F(CutOffRoads, TwoSeparateStreetsOfEqualSizeHaveNoMainComponentToFallBackOn) {
  const std::map<std::string, std::string> road{{"highway", "residential"}};
  // OSRM's "2 unconnected parallel ways": a-b-c and, 100 m south, d-e-f.
  const maps::RoadGraph g = import({maps::testing::at(1, 0, 0), maps::testing::at(2, 100, 0), maps::testing::at(3, 200, 0),
                                    maps::testing::at(4, 0, -100), maps::testing::at(5, 100, -100), maps::testing::at(6, 200, -100)},
                                   {{10, {1, 2, 3}, road}, {11, {4, 5, 6}, road}});
  ASSERT_EQ(g.main_component_nodes(), g.runner_up_component_nodes());
  const maps::EdgeSnapper snapper(g);
  maps::SnapResult from, to;
  EXPECT_TRUE(plan(g, snapper, at(g, 0, -100), at(g, 100, -100), from, to));
  EXPECT_TRUE(plan(g, snapper, at(g, 0, 0), at(g, 200, 0), from, to));
  EXPECT_FALSE(plan(g, snapper, at(g, 0, 0), at(g, 0, -100), from, to));
  EXPECT_FALSE(plan(g, snapper, at(g, 200, -100), at(g, 100, 0), from, to));
}

}  // namespace
}  // namespace corridor::planner
