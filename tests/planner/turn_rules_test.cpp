// Turn-aware routing on small OSM files, as OSRM's scenario tests do it: a map, a trip, and the
// streets the route must (or must not) take. Every rule the importer and the profile implement has
// a case here: via-node and via-way restrictions, no_ and only_, restriction modes, except, U-turns,
// turn costs and the side of the road, and physical limits. Dijkstra and D* Lite must agree on each.
#include <gtest/gtest.h>

#include <algorithm>

#include "maps/osm_import.hpp"
#include "planner/dstar_lite.hpp"
#include "planner/one_to_one_search.hpp"
#include "planner/route_steps.hpp"
#include "tests/maps/osm_fixture.hpp"
#include "tests/planner/test_graphs.hpp"

namespace corridor::planner {
namespace {

using maps::testing::at;
using maps::testing::FixtureMember;
using maps::testing::FixtureRelation;
using maps::testing::FixtureWay;

using Tags = std::map<std::string, std::string>;

// A plus-shaped junction 2 with four 100 m arms (West 1-2, East 2-3, South 4-2, North 2-5) inside a
// ring road through 1, 6, 5, 7, 3, 9, 4, 8:
//
//   6 ---- 5 ---- 7
//   |      |      |
//   1 ---- 2 ---- 3 -- 10 (a dead-end spur)
//   |      |      |
//   8 ---- 4 ---- 9
enum Way : long long { kWest = 20, kEast = 21, kSouth = 22, kNorth = 23, kRing = 30, kSpur = 40 };

maps::RoadGraph plus_map(const std::vector<FixtureRelation>& relations, const std::map<long long, Tags>& extra_way_tags = {},
                         bool left_hand_traffic = false) {
  auto tags = [&](long long id, const char* name) {
    Tags t{{"highway", "residential"}, {"name", name}};
    if (const auto it = extra_way_tags.find(id); it != extra_way_tags.end()) t.insert(it->second.begin(), it->second.end());
    return t;
  };
  maps::testing::TempDir dir;
  const auto file = dir.path() / "plus.osm";
  maps::testing::write_osm(file,
                           {at(1, 0, 100), at(2, 100, 100), at(3, 200, 100), at(4, 100, 0), at(5, 100, 200), at(6, 0, 200),
                            at(7, 200, 200), at(8, 0, 0), at(9, 200, 0), at(10, 300, 100)},
                           {{kWest, {1, 2}, tags(kWest, "West")},
                            {kEast, {2, 3}, tags(kEast, "East")},
                            {kSouth, {4, 2}, tags(kSouth, "South")},
                            {kNorth, {2, 5}, tags(kNorth, "North")},
                            {kRing, {1, 6, 5, 7, 3, 9, 4, 8, 1}, tags(kRing, "Ring")},
                            {kSpur, {3, 10}, tags(kSpur, "Spur")}},
                           relations);
  maps::OsmImportOptions options;
  options.show_progress = false;
  options.left_hand_traffic = left_hand_traffic;
  return maps::import_osm(file, options);
}

FixtureRelation restriction(std::vector<FixtureMember> members, Tags tags) {
  static long long next_id = 900;
  tags.emplace("type", "restriction");
  return {next_id++, std::move(members), std::move(tags)};
}

EdgeId edge(const maps::RoadGraph& g, long long from_osm, long long to_osm) {
  for (EdgeId e : g.edges()) {
    if (g.osm_node(g.tail(e)).v == from_osm && g.osm_node(g.head(e)).v == to_osm) return e;
  }
  ADD_FAILURE() << "no edge " << from_osm << " -> " << to_osm;
  return EdgeId{0};
}

// The middle of the road between two OSM nodes, in both directions.
std::vector<EdgePoint> middle_of(const maps::RoadGraph& g, long long a, long long b) {
  const EdgeId e = edge(g, a, b);
  return testing::with_twin(g, {e, g.length_m(e) / 2});
}

// On the Ring 50 m west of 5 (the Ring's edge 5 -> 1 runs through 6), in both directions.
std::vector<EdgePoint> ring_west_of_5(const maps::RoadGraph& g) { return testing::with_twin(g, {edge(g, 5, 1), 50.0}); }

struct Trip {
  Route route;
  std::vector<long long> ways;  // OSM ways driven, repeats collapsed
};

// Dijkstra's route, checked against A* and D* Lite on the same search graph.
Trip drive(const maps::RoadGraph& g, const VehicleProfile& profile, std::vector<EdgePoint> starts,
           std::vector<EdgePoint> goals) {
  const CostOverlay overlay(g);
  const TravelCost cost(g, overlay, profile);
  OneToOneSearch search;
  Trip t;
  t.route = search.run(SearchSpace(cost, starts, goals), false);
  const Route astar = search.run(SearchSpace(cost, starts, goals), true);
  DStarLite dstar(cost, starts, goals);
  dstar.replan();
  EXPECT_EQ(astar.found, t.route.found);
  EXPECT_EQ(dstar.route().found, t.route.found);
  if (t.route.found) {
    EXPECT_NEAR(astar.travel_time_s, t.route.travel_time_s, 1e-9);
    EXPECT_NEAR(dstar.cost_to_goal_s(), t.route.travel_time_s, 1e-9);
    EXPECT_NEAR(dstar.route().travel_time_s, t.route.travel_time_s, 1e-9);
  }
  for (EdgeId e : t.route.edges) {
    if (t.ways.empty() || t.ways.back() != g.osm_way(e).v) t.ways.push_back(g.osm_way(e).v);
  }
  return t;
}

// Heading north on South, to the middle of West: straight ahead is a left turn at 2.
Trip south_to_west(const maps::RoadGraph& g, const VehicleProfile& p = ambulance_profile()) {
  return drive(g, p, {{edge(g, 4, 2), 50.0}}, middle_of(g, 1, 2));
}

const std::vector<long long> kLeftAtTwo{kSouth, kWest};

TEST(TurnRules, WithoutRestrictionsTheLeftTurnIsTaken) {
  const auto g = plus_map({});
  EXPECT_EQ(south_to_west(g).ways, kLeftAtTwo);
}

TEST(TurnRules, NoTurnViaNodeForcesADetour) {
  const auto g = plus_map({restriction({{'w', kSouth, "from"}, {'n', 2, "via"}, {'w', kWest, "to"}}, {{"restriction", "no_left_turn"}})});
  const Trip t = south_to_west(g);
  ASSERT_TRUE(t.route.found);
  EXPECT_NE(t.ways, kLeftAtTwo);
  for (std::size_t i = 1; i < t.route.edges.size(); ++i) {
    EXPECT_FALSE(t.route.edges[i - 1] == edge(g, 4, 2) && t.route.edges[i] == edge(g, 2, 1)) << "took the banned turn";
  }
  // The restriction binds only that turn: from East, West is straight on.
  EXPECT_EQ(drive(g, ambulance_profile(), {{edge(g, 3, 2), 50.0}}, middle_of(g, 1, 2)).ways,
            (std::vector<long long>{kEast, kWest}));
}

TEST(TurnRules, ExceptNamingEmergencyOrPsvLiftsTheRestriction) {
  for (const char* except : {"emergency", "psv", "bicycle;psv"}) {
    const auto g = plus_map({restriction({{'w', kSouth, "from"}, {'n', 2, "via"}, {'w', kWest, "to"}},
                                         {{"restriction", "no_left_turn"}, {"except", except}})});
    EXPECT_EQ(south_to_west(g).ways, kLeftAtTwo) << except;
    VehicleProfile strict = ambulance_profile();
    strict.except_classes = 0;
    EXPECT_NE(south_to_west(g, strict).ways, kLeftAtTwo) << except;
  }
  const auto g = plus_map({restriction({{'w', kSouth, "from"}, {'n', 2, "via"}, {'w', kWest, "to"}},
                                       {{"restriction", "no_left_turn"}, {"except", "bicycle"}})});
  EXPECT_NE(south_to_west(g).ways, kLeftAtTwo);
}

// An `except` lifts a ban for the classes the vehicle belongs to: the ambulance is a motorcar, the
// fire engine an hgv (OSRM's car takes except=motorcar|motor_vehicle|vehicle the same way).
TEST(TurnRules, ExceptLiftsTheBanForTheVehicleClassesItNames) {
  struct Case {
    const char* except;
    bool ambulance_lifted;
    bool fire_engine_lifted;
  };
  for (const Case& c : {Case{"motorcar", true, false}, Case{"hgv", false, true}, Case{"motor_vehicle", true, true},
                        Case{"bus;bicycle", false, false}, Case{"hgv; motorcar", true, true}}) {
    const auto g = plus_map({restriction({{'w', kSouth, "from"}, {'n', 2, "via"}, {'w', kWest, "to"}},
                                         {{"restriction", "no_left_turn"}, {"except", c.except}})});
    EXPECT_EQ(south_to_west(g).ways == kLeftAtTwo, c.ambulance_lifted) << c.except;
    EXPECT_EQ(south_to_west(g, fire_engine_profile()).ways == kLeftAtTwo, c.fire_engine_lifted) << c.except;
  }
}

// A via-way restriction whose from way runs through the junction where the via ways start does not
// say which side it binds (OSRM's "Ambiguous from/to ways"): it is dropped, not applied to both
// sides. Split the from way at that junction and it binds its one side.
//
//   a
//   |
//   b --- d --- e     from abc (or ab) via bd, de to ef: no_right_turn
//   |           |
//   c           f
TEST(TurnRules, AViaWayRestrictionFromAWayThroughItsJunctionIsAmbiguous) {
  using maps::testing::at;
  auto trip = [](bool split) {
    maps::testing::TempDir dir;
    const Tags road{{"highway", "residential"}};
    std::vector<FixtureWay> ways{{11, {2, 4}, road}, {12, {4, 5}, road}, {13, {5, 6}, road}};
    if (split) {
      ways.push_back({10, {1, 2}, road});
      ways.push_back({14, {2, 3}, road});
    } else {
      ways.push_back({10, {1, 2, 3}, road});
    }
    maps::testing::write_osm(dir.path() / "amb.osm",
                             {at(1, 0, 200), at(2, 0, 100), at(3, 0, 0), at(4, 100, 100), at(5, 200, 100), at(6, 200, 0)}, ways,
                             {restriction({{'w', 10, "from"}, {'w', 11, "via"}, {'w', 12, "via"}, {'w', 13, "to"}},
                                          {{"restriction", "no_right_turn"}})});
    maps::OsmImportOptions options;
    options.show_progress = false;
    const auto g = maps::import_osm(dir.path() / "amb.osm", options);
    return drive(g, ambulance_profile(), {{edge(g, 1, 2), 0.0}}, {{edge(g, 5, 6), 50.0}});
  };
  const Trip ambiguous = trip(false);
  ASSERT_TRUE(ambiguous.route.found);
  // Straight through, as OSRM routes it: 100 + 100 + 100 + 50 m, not down to c and back (+200 m).
  EXPECT_EQ(ambiguous.ways, (std::vector<long long>{10, 11, 12, 13}));
  EXPECT_NEAR(ambiguous.route.length_m, 350.0, 2.0);
  const Trip one_sided = trip(true);
  ASSERT_TRUE(one_sided.route.found);
  // From a the ban binds: down to the dead end at c, turn there, and back up.
  EXPECT_EQ(one_sided.ways, (std::vector<long long>{10, 14, 11, 12, 13}));
  EXPECT_NEAR(one_sided.route.length_m, 550.0, 2.0);
}

// Two restrictions forbid the same turn with different except lists: each binds whom its own list
// does not name. except=motorcar and except=hgv together bind both vehicles; two lists that both
// name psv lift the ban for both.
TEST(TurnRules, TwoExceptedBansOnOneTurnEachBindWhomTheirListLeavesOut) {
  auto both = [](const char* first, const char* second) {
    return plus_map({restriction({{'w', kSouth, "from"}, {'n', 2, "via"}, {'w', kWest, "to"}}, {{"restriction", "no_left_turn"}, {"except", first}}),
                     restriction({{'w', kSouth, "from"}, {'n', 2, "via"}, {'w', kWest, "to"}}, {{"restriction", "no_left_turn"}, {"except", second}})});
  };
  const auto split = both("motorcar", "hgv");
  EXPECT_NE(south_to_west(split).ways, kLeftAtTwo);
  EXPECT_NE(south_to_west(split, fire_engine_profile()).ways, kLeftAtTwo);
  const auto shared = both("motorcar;psv", "hgv;psv");
  EXPECT_EQ(south_to_west(shared).ways, kLeftAtTwo);
  EXPECT_EQ(south_to_west(shared, fire_engine_profile()).ways, kLeftAtTwo);
}

TEST(TurnRules, TurnsBannedOnRedOnlyStayOpen) {
  for (const char* value : {"no_left_turn_on_red", "no_turn_on_red"}) {
    const auto g = plus_map({restriction({{'w', kSouth, "from"}, {'n', 2, "via"}, {'w', kWest, "to"}}, {{"restriction", value}})});
    EXPECT_EQ(south_to_west(g).ways, kLeftAtTwo) << value;
  }
}

TEST(TurnRules, ModeSpecificRestrictionsBindTheirModesOnly) {
  auto with_key = [](const char* key) {
    return plus_map({restriction({{'w', kSouth, "from"}, {'n', 2, "via"}, {'w', kWest, "to"}}, {{key, "no_left_turn"}})});
  };
  for (const char* key : {"restriction:motorcar", "restriction:motor_vehicle", "restriction:vehicle", "restriction:emergency"}) {
    EXPECT_NE(south_to_west(with_key(key)).ways, kLeftAtTwo) << key;
  }
  // Trucks only: binds the fire engine, not the ambulance.
  const auto hgv = with_key("restriction:hgv");
  EXPECT_EQ(south_to_west(hgv).ways, kLeftAtTwo);
  EXPECT_NE(south_to_west(hgv, fire_engine_profile()).ways, kLeftAtTwo);
  // Ignored: other modes, and restriction:conditional (see docs/routing.md).
  EXPECT_EQ(south_to_west(with_key("restriction:bicycle")).ways, kLeftAtTwo);
  EXPECT_EQ(south_to_west(with_key("restriction:conditional")).ways, kLeftAtTwo);
}

TEST(TurnRules, OnlyStraightOnForbidsEveryOtherWayOut) {
  const auto g = plus_map({restriction({{'w', kSouth, "from"}, {'n', 2, "via"}, {'w', kNorth, "to"}}, {{"restriction", "only_straight_on"}})});
  for (const auto& [a, b] : std::vector<std::pair<long long, long long>>{{1, 2}, {2, 3}}) {
    const Trip t = drive(g, ambulance_profile(), {{edge(g, 4, 2), 50.0}}, middle_of(g, a, b));
    ASSERT_TRUE(t.route.found);
    ASSERT_GE(t.ways.size(), 2u);
    EXPECT_EQ(t.ways[1], kNorth) << "to " << a << "-" << b;
  }
}

TEST(TurnRules, NoUturnRestrictionAtADeadEndSpur) {
  // The spur 3-10 ends at 10, where a U-turn is the only way on; no_u_turn there strands the vehicle.
  const auto open = plus_map({});
  const Trip back = drive(open, ambulance_profile(), {{edge(open, 3, 10), 20.0}}, middle_of(open, 2, 3));
  ASSERT_TRUE(back.route.found);
  EXPECT_EQ(back.route.edges[1], edge(open, 10, 3));
  const auto banned = plus_map({restriction({{'w', kSpur, "from"}, {'n', 10, "via"}, {'w', kSpur, "to"}}, {{"restriction", "no_u_turn"}})});
  EXPECT_FALSE(drive(banned, ambulance_profile(), {{edge(banned, 3, 10), 20.0}}, middle_of(banned, 2, 3)).route.found);
}

TEST(TurnRules, ViaWayRestrictionBindsOnlyThePathThroughIt) {
  // From South through North, left onto the Ring: forbidden. The Ring runs through 5 both ways, and
  // "left" names the west side only. From West through North onto the Ring: fine.
  const auto g = plus_map({restriction({{'w', kSouth, "from"}, {'w', kNorth, "via"}, {'w', kRing, "to"}}, {{"restriction", "no_left_turn"}})});
  const auto goal = ring_west_of_5(g);
  const Trip from_south = drive(g, ambulance_profile(), {{edge(g, 4, 2), 50.0}}, goal);
  ASSERT_TRUE(from_south.route.found);
  const std::vector<EdgeId> banned{edge(g, 4, 2), edge(g, 2, 5), edge(g, 5, 1)};
  EXPECT_EQ(std::search(from_south.route.edges.begin(), from_south.route.edges.end(), banned.begin(), banned.end()),
            from_south.route.edges.end());
  EXPECT_EQ(drive(g, ambulance_profile(), {{edge(g, 1, 2), 50.0}}, goal).ways, (std::vector<long long>{kWest, kNorth, kRing}));
  // The same trip with no restriction goes straight up North.
  EXPECT_EQ(drive(plus_map({}), ambulance_profile(), {{edge(g, 4, 2), 50.0}}, goal).ways,
            (std::vector<long long>{kSouth, kNorth, kRing}));
  // Right onto the Ring from the same path is not what the restriction names.
  EXPECT_EQ(drive(g, ambulance_profile(), {{edge(g, 4, 2), 50.0}}, testing::with_twin(g, {edge(g, 5, 3), 50.0})).ways,
            (std::vector<long long>{kSouth, kNorth, kRing}));
}

// Two restrictions that overlap: a via-way one through North, and a via-node one on North's far
// end. The copy of North that remembers "came from South" must still carry the via-node ban,
// whichever relation comes first in the file.
TEST(TurnRules, OverlappingRestrictionsKeepBothMeanings) {
  const auto via_way = restriction({{'w', kSouth, "from"}, {'w', kNorth, "via"}, {'w', kRing, "to"}}, {{"restriction", "no_left_turn"}});
  const auto via_node = restriction({{'w', kNorth, "from"}, {'n', 5, "via"}, {'w', kRing, "to"}}, {{"restriction", "no_right_turn"}});
  for (const auto& relations : std::vector<std::vector<FixtureRelation>>{{via_way, via_node}, {via_node, via_way}}) {
    const auto g = plus_map(relations);
    const Trip t = drive(g, ambulance_profile(), {{edge(g, 4, 2), 50.0}}, testing::with_twin(g, {edge(g, 5, 3), 50.0}));
    ASSERT_TRUE(t.route.found);
    const std::vector<EdgeId> right{edge(g, 2, 5), edge(g, 5, 3)};
    EXPECT_EQ(std::search(t.route.edges.begin(), t.route.edges.end(), right.begin(), right.end()), t.route.edges.end())
        << "the via-node ban was lost on the copy";
  }
}

TEST(TurnRules, OnlyViaWayMustFollowTheWholePath) {
  // Only South -> North -> Ring: from South, every other exit at 2 is closed.
  const auto g = plus_map({restriction({{'w', kSouth, "from"}, {'w', kNorth, "via"}, {'w', kRing, "to"}}, {{"restriction", "only_left_turn"}})});
  const Trip t = drive(g, ambulance_profile(), {{edge(g, 4, 2), 50.0}}, middle_of(g, 2, 3));
  ASSERT_TRUE(t.route.found);
  ASSERT_GE(t.ways.size(), 3u);
  EXPECT_EQ((std::vector<long long>{t.ways[0], t.ways[1], t.ways[2]}), (std::vector<long long>{kSouth, kNorth, kRing}));
}

TEST(TurnRules, UturnsOnlyAtDeadEndsUnlessTheProfileAllowsThem) {
  const auto g = plus_map({});
  // Heading north on South with the goal just behind: no U-turn at 2, so round a block.
  const auto behind = middle_of(g, 2, 4);
  const Trip loop = drive(g, ambulance_profile(), {{edge(g, 4, 2), 60.0}}, behind);
  ASSERT_TRUE(loop.route.found);
  EXPECT_GT(loop.route.length_m, 300.0);
  for (std::size_t i = 1; i < loop.route.edges.size(); ++i) EXPECT_NE(loop.route.edges[i], g.twin(loop.route.edges[i - 1]));
  VehicleProfile turning = ambulance_profile();
  turning.uturn_policy = UturnPolicy::anywhere;
  turning.uturn_penalty_s = 5.0;
  const Trip uturn = drive(g, turning, {{edge(g, 4, 2), 60.0}}, behind);
  EXPECT_EQ(uturn.route.edges, (std::vector<EdgeId>{edge(g, 4, 2), edge(g, 2, 4)}));
  EXPECT_LT(uturn.route.length_m, 100.0);
  // A high enough penalty makes the loop cheaper again.
  turning.uturn_penalty_s = 600.0;
  EXPECT_GT(drive(g, turning, {{edge(g, 4, 2), 60.0}}, behind).route.length_m, 300.0);
}

TEST(TurnRules, TurnCostsPreferStraightThenTheTurnThatDoesNotCrossTraffic) {
  const auto rht = plus_map({});
  // Three goals 50 m past the junction: ahead, right and left.
  std::vector<EdgePoint> goals;
  for (const auto& [a, b] : std::vector<std::pair<long long, long long>>{{2, 5}, {2, 3}, {2, 1}}) {
    goals.push_back({edge(rht, a, b), 50.0});
  }
  const EdgePoint start{edge(rht, 4, 2), 50.0};
  EXPECT_EQ(drive(rht, ambulance_profile(), {start}, goals).ways, (std::vector<long long>{kSouth, kNorth}));
  goals.erase(goals.begin());  // right or left only
  EXPECT_EQ(drive(rht, ambulance_profile(), {start}, goals).ways, (std::vector<long long>{kSouth, kEast}));
  const Trip plain = drive(rht, ambulance_profile(), {start}, goals);
  // Where traffic keeps left, the left turn is the one that does not cross it.
  const auto lht = plus_map({}, {}, true);
  std::vector<EdgePoint> lht_goals{{edge(lht, 2, 3), 50.0}, {edge(lht, 2, 1), 50.0}};
  EXPECT_EQ(drive(lht, ambulance_profile(), {{edge(lht, 4, 2), 50.0}}, lht_goals).ways, (std::vector<long long>{kSouth, kWest}));
  // The turn's cost is in the route's time: a right angle costs half the turn penalty.
  const double driving = 100.0 / (30.0 / 3.6);  // 100 m at the residential default of 30 km/h
  EXPECT_NEAR(plain.route.travel_time_s, driving + ambulance_profile().turn_penalty_s / 2, 0.05);
}

TEST(TurnRules, PhysicalLimitsStopTheVehiclesThatDoNotFit) {
  const auto goal_north = [](const maps::RoadGraph& g) { return ring_west_of_5(g); };
  for (const auto& [limit, value] : std::vector<std::pair<std::string, std::string>>{
           {"maxheight", "3.2"}, {"maxwidth", "2.4"}, {"maxweight", "7.5"}}) {
    const auto g = plus_map({}, {{kNorth, {{limit, value}}}});
    const EdgePoint start{edge(g, 4, 2), 50.0};
    const Trip ambulance = drive(g, ambulance_profile(), {start}, goal_north(g));
    EXPECT_EQ(ambulance.ways, (std::vector<long long>{kSouth, kNorth, kRing})) << limit;
    const Trip fire = drive(g, fire_engine_profile(), {start}, goal_north(g));
    ASSERT_TRUE(fire.route.found) << limit;
    EXPECT_EQ(std::count(fire.ways.begin(), fire.ways.end(), kNorth), 0) << limit;
  }
}

// A four-arm roundabout, driven counter-clockwise (traffic keeps right): entering from the South arm,
// East is the first exit, North the second, West the third.
TEST(TurnRules, RoundaboutIsOneStepWithItsExitNumber) {
  maps::testing::TempDir dir;
  const auto file = dir.path() / "roundabout.osm";
  const Tags arm{{"highway", "residential"}};
  auto named = [&](const char* name) {
    Tags t = arm;
    t["name"] = name;
    return t;
  };
  maps::testing::write_osm(file,
                           {at(1, 100, 115), at(2, 115, 100), at(3, 100, 85), at(4, 85, 100), at(11, 100, 250),
                            at(12, 250, 100), at(13, 100, -50), at(14, -50, 100), at(21, 250, 250), at(22, 250, -50),
                            at(23, -50, -50), at(24, -50, 250)},
                           {{50, {1, 4, 3, 2, 1}, {{"highway", "residential"}, {"junction", "roundabout"}, {"name", "Circus"}}},
                            {51, {1, 11}, named("North Arm")},
                            {52, {2, 12}, named("East Arm")},
                            {53, {3, 13}, named("South Arm")},
                            {54, {4, 14}, named("West Arm")},
                            {55, {11, 21, 12, 22, 13, 23, 14, 24, 11}, named("Outer")}});
  maps::OsmImportOptions options;
  options.show_progress = false;
  const auto g = maps::import_osm(file, options);
  const EdgePoint start{edge(g, 13, 3), 20.0};
  for (const auto& [to, exit, name] : std::vector<std::tuple<long long, int, std::string>>{
           {12, 1, "East Arm"}, {11, 2, "North Arm"}, {14, 3, "West Arm"}}) {
    const EdgeId out = edge(g, to == 12 ? 2 : to == 11 ? 1 : 4, to);
    const Trip t = drive(g, ambulance_profile(), {start}, {{out, 50.0}});
    ASSERT_TRUE(t.route.found) << name;
    const auto steps = route_steps(g, t.route);
    ASSERT_EQ(steps.size(), 3u) << name;  // depart, roundabout, arrive
    EXPECT_EQ(steps[1].maneuver, ManeuverType::roundabout) << name;
    EXPECT_EQ(steps[1].exit, exit) << name;
    EXPECT_EQ(steps[1].name, name);
  }
}


// West (0-1), then Gate Street (1-2-3) with a gate at 2 or a 120 m longer Detour (1-5-6-3), then
// East (3-4). With `side_road`, a dead-end Side (2-7) makes the gate's node a junction.
maps::RoadGraph gate_map(bool side_road, bool with_detour = true) {
  maps::testing::TempDir dir;
  const auto file = dir.path() / "gate.osm";
  auto named = [](const char* name) { return Tags{{"highway", "residential"}, {"name", name}}; };
  std::vector<FixtureWay> ways{{60, {0, 1}, named("West")}, {61, {1, 2, 3}, named("Gate Street")}, {63, {3, 4}, named("East")}};
  if (with_detour) ways.push_back({62, {1, 5, 6, 3}, named("Detour")});
  if (side_road) ways.push_back({64, {2, 7}, named("Side")});
  maps::testing::write_osm(file,
                           {at(0, -100, 0), at(1, 0, 0), at(2, 100, 0, {{"barrier", "gate"}}), at(3, 200, 0), at(4, 300, 0),
                            at(5, 0, 60), at(6, 200, 60), at(7, 100, -80)},
                           ways, {});
  maps::OsmImportOptions options;
  options.show_progress = false;
  return maps::import_osm(file, options);
}

// A gate costs the profile's barrier_delay_s: a route goes round it when that saves time, and
// through it, charged exactly once, when there is no other way; the same for a gate at a junction.
// A trip that ends at the gate, or starts past it, is not charged for it.
TEST(TurnRules, AGateCostsTheProfilesBarrierDelay) {
  VehicleProfile no_delay = ambulance_profile();
  no_delay.barrier_delay_s = 0.0;
  for (const bool side_road : {false, true}) {
    const auto g = gate_map(side_road);
    const auto from = middle_of(g, 0, 1), to = middle_of(g, 3, 4);
    const Trip free = drive(g, no_delay, from, to);
    EXPECT_EQ(free.ways, (std::vector<long long>{60, 61, 63})) << side_road;  // the shorter street
    const Trip with_gate = drive(g, ambulance_profile(), from, to);
    EXPECT_EQ(with_gate.ways, (std::vector<long long>{60, 62, 63})) << side_road;  // 120 m round is under 30 s
    EXPECT_LT(with_gate.route.travel_time_s, free.route.travel_time_s + 30.0);

    const auto only = gate_map(side_road, false);
    const auto from_only = middle_of(only, 0, 1), to_only = middle_of(only, 3, 4);
    auto time = [&](const VehicleProfile& p, const std::vector<EdgePoint>& a, const std::vector<EdgePoint>& b) {
      return drive(only, p, a, b).route.travel_time_s;
    };
    EXPECT_NEAR(time(ambulance_profile(), from_only, to_only), time(no_delay, from_only, to_only) + 30.0, 1e-9) << side_road;
    // Up to the gate, and on from just past it: no delay.
    const EdgeId up_to_gate = edge(only, 1, 2), past_gate = edge(only, 2, 3);
    const std::vector<EdgePoint> at_gate{{up_to_gate, only.length_m(up_to_gate)}};
    const std::vector<EdgePoint> just_past{{past_gate, 1.0}};
    EXPECT_NEAR(time(ambulance_profile(), from_only, at_gate), time(no_delay, from_only, at_gate), 1e-9) << side_road;
    EXPECT_NEAR(time(ambulance_profile(), just_past, to_only), time(no_delay, just_past, to_only), 1e-9) << side_road;
  }
}

// A gate on a bend inside one way adds its delay and nothing else: the bend there is no turn (no
// turn cost, no step), as it was before the gate made the bend a node.
TEST(TurnRules, AGateOnABendIsNoTurn) {
  auto bend_map = [](bool gate) {
    maps::testing::TempDir dir;
    const auto file = dir.path() / "bend.osm";
    auto named = [](const char* name) { return Tags{{"highway", "residential"}, {"name", name}}; };
    maps::testing::write_osm(file,
                             {at(0, -100, 0), at(1, 0, 0), at(2, 100, 0, gate ? Tags{{"barrier", "gate"}} : Tags{}), at(3, 100, 100),
                              at(4, 100, 200)},
                             {{60, {0, 1}, named("West")}, {70, {1, 2, 3}, named("Bend Road")}, {63, {3, 4}, named("North")}}, {});
    maps::OsmImportOptions options;
    options.show_progress = false;
    return maps::import_osm(file, options);
  };
  const auto with_gate = bend_map(true), without = bend_map(false);
  const Trip through = drive(with_gate, ambulance_profile(), middle_of(with_gate, 0, 1), middle_of(with_gate, 3, 4));
  const Trip plain = drive(without, ambulance_profile(), middle_of(without, 0, 1), middle_of(without, 3, 4));
  ASSERT_TRUE(through.route.found && plain.route.found);
  EXPECT_NEAR(through.route.travel_time_s, plain.route.travel_time_s + ambulance_profile().barrier_delay_s, 1e-9);
  std::vector<std::string> names;
  for (const RouteStep& st : route_steps(with_gate, through.route)) names.push_back(st.name);
  EXPECT_EQ(names, (std::vector<std::string>{"West", "Bend Road", "North", "North"}));
}

// Turning back at a gate that closes a dead end is a U-turn all the same: the gate takes away only
// the bends along its way, not the turn back.
TEST(TurnRules, AUturnAtADeadEndGateIsAStep) {
  maps::testing::TempDir dir;
  const auto file = dir.path() / "lane.osm";
  maps::testing::write_osm(file, {at(0, -100, 0), at(1, 0, 0), at(2, 100, 0, Tags{{"barrier", "gate"}})},
                           {{60, {0, 1}, Tags{{"highway", "residential"}, {"name", "West"}}},
                            {70, {1, 2}, Tags{{"highway", "residential"}, {"name", "Gate Lane"}}}},
                           {});
  maps::OsmImportOptions options;
  options.show_progress = false;
  const auto g = maps::import_osm(file, options);
  ASSERT_EQ(g.stop_at(g.head(edge(g, 1, 2))), true);
  const Trip back = drive(g, ambulance_profile(), {{edge(g, 1, 2), 50.0}}, {{edge(g, 2, 1), 80.0}});
  ASSERT_TRUE(back.route.found);
  ASSERT_EQ(back.route.edges, (std::vector<EdgeId>{edge(g, 1, 2), edge(g, 2, 1)}));
  const auto steps = route_steps(g, back.route);
  EXPECT_TRUE(std::any_of(steps.begin(), steps.end(), [](const RouteStep& st) { return st.modifier == TurnModifier::uturn; }));
}

// A trip that starts or ends within a metre of a junction starts or ends at it: no step of 0.3 m on
// the street it leaves (or reaches) at once. Two metres is a real step and stays.
TEST(TurnRules, AStepShorterThanAMetreAtEitherEndIsFoldedIntoItsNeighbour) {
  const auto g = plus_map({});
  const EdgeId west = edge(g, 1, 2), north = edge(g, 2, 5);
  auto names = [&](const EdgePoint& from, const EdgePoint& to) {
    const Trip t = drive(g, ambulance_profile(), {from}, {to});
    EXPECT_TRUE(t.route.found);
    std::vector<std::string> out;
    double total_m = 0;
    for (const RouteStep& s : route_steps(g, t.route)) {
      out.push_back(std::string(to_string(s.maneuver)) + ":" + s.name);
      total_m += s.distance_m;
    }
    EXPECT_NEAR(total_m, g.length_m(west) - from.offset_m + to.offset_m, 1e-6);  // no metre lost
    return out;
  };
  using V = std::vector<std::string>;
  EXPECT_EQ(names({west, g.length_m(west) - 0.3}, {north, 50.0}), (V{"depart:North", "arrive:North"}));
  EXPECT_EQ(names({west, 50.0}, {north, 0.3}), (V{"depart:West", "arrive:West"}));
  EXPECT_EQ(names({west, g.length_m(west) - 2.0}, {north, 2.0}), (V{"depart:West", "turn:North", "arrive:North"}));
}

}  // namespace
}  // namespace corridor::planner
