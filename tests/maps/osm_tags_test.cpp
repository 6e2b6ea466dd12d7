#include "maps/osm_tags.hpp"

#include <gtest/gtest.h>

namespace corridor::maps {
namespace {

TEST(MaxspeedParsing, PlainNumbersAreKmh) {
  EXPECT_DOUBLE_EQ(*parse_maxspeed_kmh("50"), 50.0);
  EXPECT_DOUBLE_EQ(*parse_maxspeed_kmh(" 80 "), 80.0);
  EXPECT_DOUBLE_EQ(*parse_maxspeed_kmh("30 km/h"), 30.0);
  EXPECT_DOUBLE_EQ(*parse_maxspeed_kmh("7.5"), 7.5);
}

TEST(MaxspeedParsing, MphAndKnotsAreConverted) {
  EXPECT_NEAR(*parse_maxspeed_kmh("30 mph"), 48.28032, 1e-9);
  EXPECT_NEAR(*parse_maxspeed_kmh("20mph"), 32.18688, 1e-9);
  EXPECT_NEAR(*parse_maxspeed_kmh("10 knots"), 18.52, 1e-9);
}

TEST(MaxspeedParsing, SpecialWords) {
  EXPECT_DOUBLE_EQ(*parse_maxspeed_kmh("none"), 140.0);
  EXPECT_DOUBLE_EQ(*parse_maxspeed_kmh("walk"), 6.0);
  EXPECT_FALSE(parse_maxspeed_kmh("signals").has_value());
  EXPECT_FALSE(parse_maxspeed_kmh("variable").has_value());
  EXPECT_FALSE(parse_maxspeed_kmh("").has_value());
  EXPECT_FALSE(parse_maxspeed_kmh("fast").has_value());
  EXPECT_FALSE(parse_maxspeed_kmh("-20").has_value());
  EXPECT_FALSE(parse_maxspeed_kmh("50 furlongs").has_value());
}

TEST(MaxspeedParsing, ImplicitCountryValues) {
  EXPECT_DOUBLE_EQ(*parse_maxspeed_kmh("DE:urban"), 50.0);
  EXPECT_DOUBLE_EQ(*parse_maxspeed_kmh("DE:rural"), 100.0);
  EXPECT_DOUBLE_EQ(*parse_maxspeed_kmh("FR:rural"), 80.0);
  EXPECT_DOUBLE_EQ(*parse_maxspeed_kmh("CH:motorway"), 120.0);
  EXPECT_DOUBLE_EQ(*parse_maxspeed_kmh("RU:urban"), 60.0);
  EXPECT_DOUBLE_EQ(*parse_maxspeed_kmh("XX:urban"), 50.0);  // unknown country: generic value
  EXPECT_NEAR(*parse_maxspeed_kmh("GB:nsl_single"), 96.56064, 1e-9);
  EXPECT_DOUBLE_EQ(*parse_maxspeed_kmh("DE:zone30"), 30.0);
  EXPECT_DOUBLE_EQ(*parse_maxspeed_kmh("DE:zone:20"), 20.0);
  EXPECT_DOUBLE_EQ(*parse_maxspeed_kmh("DE:living_street"), 7.0);
  EXPECT_FALSE(parse_maxspeed_kmh("DE:nonsense").has_value());
}

TEST(MaxspeedParsing, FirstOfSeveralValues) { EXPECT_DOUBLE_EQ(*parse_maxspeed_kmh("50;30"), 50.0); }

WayTags road(std::string_view highway) {
  WayTags t;
  t.highway = highway;
  return t;
}

TEST(WayRules, DrivableClassesAreKeptOthersDropped) {
  for (auto h : {"motorway", "trunk", "primary", "secondary", "tertiary", "unclassified", "residential",
                 "living_street", "service", "motorway_link", "trunk_link", "primary_link", "secondary_link",
                 "tertiary_link"}) {
    EXPECT_TRUE(interpret_way(road(h)).has_value()) << h;
  }
  for (auto h : {"footway", "cycleway", "path", "steps", "track", "pedestrian", "bridleway", "construction", ""}) {
    EXPECT_FALSE(interpret_way(road(h)).has_value()) << h;
  }
}

TEST(WayRules, EmergencyYesOpensAnyHighway) {
  WayTags t = road("pedestrian");
  t.emergency = "yes";
  const auto rules = interpret_way(t);
  ASSERT_TRUE(rules.has_value());
  EXPECT_EQ(rules->road_class, RoadClass::emergency_access);
  EXPECT_TRUE(rules->forward && rules->backward);
}

TEST(WayRules, EmergencyNoClosesADrivableRoad) {
  WayTags t = road("residential");
  t.emergency = "no";
  EXPECT_FALSE(interpret_way(t).has_value());
}

TEST(WayRules, AccessRules) {
  WayTags t = road("residential");
  t.access = "no";
  EXPECT_FALSE(interpret_way(t).has_value());
  t.access = "private";  // private and destination do not stop an emergency vehicle
  EXPECT_TRUE(interpret_way(t).has_value());
  t.access = "destination";
  EXPECT_TRUE(interpret_way(t).has_value());
  t.access = "yes";
  t.motor_vehicle = "no";
  EXPECT_FALSE(interpret_way(t).has_value());
  t.motorcar = "yes";  // the most specific tag wins
  EXPECT_TRUE(interpret_way(t).has_value());
  WayTags closed = road("service");
  closed.access = "no";
  closed.emergency = "yes";  // explicitly open to emergency vehicles
  EXPECT_TRUE(interpret_way(closed).has_value());
  WayTags agri = road("service");
  agri.vehicle = "agricultural";
  EXPECT_FALSE(interpret_way(agri).has_value());
}

TEST(WayRules, Oneway) {
  WayTags t = road("residential");
  auto r = interpret_way(t);
  EXPECT_TRUE(r->forward && r->backward);
  for (auto v : {"yes", "true", "1"}) {
    t.oneway = v;
    r = interpret_way(t);
    EXPECT_TRUE(r->forward && !r->backward) << v;
  }
  for (auto v : {"-1", "reverse"}) {
    t.oneway = v;
    r = interpret_way(t);
    EXPECT_TRUE(!r->forward && r->backward) << v;
  }
  t.oneway = "no";
  r = interpret_way(t);
  EXPECT_TRUE(r->forward && r->backward);
  t.oneway = "reversible";
  EXPECT_FALSE(interpret_way(t).has_value());
  t.oneway = "yes";
  t.oneway_emergency = "no";
  r = interpret_way(t);
  EXPECT_TRUE(r->forward && r->backward);
}

TEST(WayRules, RoundaboutAndMotorwayImplyOneway) {
  WayTags t = road("primary");
  t.junction = "roundabout";
  auto r = interpret_way(t);
  EXPECT_TRUE(r->forward && !r->backward);
  t.junction = "circular";
  r = interpret_way(t);
  EXPECT_TRUE(r->forward && !r->backward);
  t.oneway = "no";  // an explicit tag overrides the implication
  r = interpret_way(t);
  EXPECT_TRUE(r->forward && r->backward);
  r = interpret_way(road("motorway"));
  EXPECT_TRUE(r->forward && !r->backward);
  r = interpret_way(road("motorway_link"));
  EXPECT_TRUE(r->forward && r->backward);
}

TEST(WayRules, SpeedFromMaxspeedOrClassDefault) {
  WayTags t = road("residential");
  auto r = interpret_way(t);
  EXPECT_DOUBLE_EQ(r->forward_speed_kmh, default_speed_kmh(RoadClass::residential));
  t.maxspeed = "DE:urban";
  r = interpret_way(t);
  EXPECT_DOUBLE_EQ(r->forward_speed_kmh, 50.0);
  t.maxspeed = "signals";  // no number: class default
  r = interpret_way(t);
  EXPECT_DOUBLE_EQ(r->forward_speed_kmh, default_speed_kmh(RoadClass::residential));
  t.maxspeed = "60";
  t.maxspeed_backward = "40";
  r = interpret_way(t);
  EXPECT_DOUBLE_EQ(r->forward_speed_kmh, 60.0);
  EXPECT_DOUBLE_EQ(r->backward_speed_kmh, 40.0);
}

TEST(WayRules, AreasAreNotRoads) {
  WayTags t = road("service");
  t.area = "yes";
  EXPECT_FALSE(interpret_way(t).has_value());
}

}  // namespace
}  // namespace corridor::maps

namespace corridor::maps {
namespace {

TEST(WayRules, AccessListsForbidOnlyWhenEveryItemDoes) {
  WayTags t = road("residential");
  t.access = "agricultural;forestry";
  EXPECT_FALSE(interpret_way(t).has_value());
  t.access = "agricultural; forestry";
  EXPECT_FALSE(interpret_way(t).has_value());
  t.access = "agricultural;destination";
  EXPECT_TRUE(interpret_way(t).has_value());
  for (const char* v : {"foot", "bicycle", "restricted", "military", "horse"}) {
    t.access = v;
    EXPECT_FALSE(interpret_way(t).has_value()) << v;
  }
  t.access = "no";
  t.motor_vehicle = "yes";  // the more specific tag decides
  EXPECT_TRUE(interpret_way(t).has_value());
}

TEST(WayRules, ConstructionClosesTheWay) {
  WayTags t = road("residential");
  for (const char* v : {"yes", "major", "widening"}) {
    t.construction = v;
    EXPECT_FALSE(interpret_way(t).has_value()) << v;
  }
  for (const char* v : {"no", "minor"}) {
    t.construction = v;
    EXPECT_TRUE(interpret_way(t).has_value()) << v;
  }
}

TEST(WayRules, ModeSpecificOnewayOverridesOneway) {
  WayTags t = road("residential");
  t.oneway = "yes";
  t.oneway_motor_vehicle = "no";
  auto r = interpret_way(t);
  ASSERT_TRUE(r.has_value());
  EXPECT_TRUE(r->forward && r->backward);
  t = road("residential");
  t.oneway_vehicle = "-1";
  r = interpret_way(t);
  ASSERT_TRUE(r.has_value());
  EXPECT_FALSE(r->forward);
  EXPECT_TRUE(r->backward);
  t.oneway_motorcar = "yes";  // more specific than oneway:vehicle
  r = interpret_way(t);
  ASSERT_TRUE(r.has_value());
  EXPECT_TRUE(r->forward);
  EXPECT_FALSE(r->backward);
  t.oneway_emergency = "no";  // the emergency exemption wins over all
  r = interpret_way(t);
  EXPECT_TRUE(r->forward && r->backward);
}

TEST(WayRules, DirectionalAccessClosesOneDirection) {
  WayTags t = road("residential");
  t.access_forward = "no";
  auto r = interpret_way(t);
  ASSERT_TRUE(r.has_value());
  EXPECT_FALSE(r->forward);
  EXPECT_TRUE(r->backward);
  t.motorcar_forward = "yes";  // more specific
  r = interpret_way(t);
  EXPECT_TRUE(r->forward);
  t = road("residential");
  t.motor_vehicle_backward = "no";
  t.motor_vehicle_forward = "no";
  EXPECT_FALSE(interpret_way(t).has_value());
  t.emergency = "yes";
  EXPECT_TRUE(interpret_way(t).has_value());
}

// A node with `barrier` and, optionally, one more tag.
NodeTags barrier_node(std::string_view barrier, std::string_view extra_key = {}, std::string_view extra = {}) {
  NodeTags t;
  t.barrier = barrier;
  if (extra_key == "bollard") t.bollard = extra;
  if (extra_key == "kerb") t.kerb = extra;
  if (extra_key == "maxheight") t.maxheight = extra;
  if (extra_key == "access") t.access = extra;
  if (extra_key == "emergency") t.emergency = extra;
  return t;
}

TEST(NodeRules, BarriersAsACarProfileReadsThem) {
  auto blocks = [](auto... tags) { return node_blocks_emergency(barrier_node(tags...)); };
  for (const char* b : {"bollard", "block", "wall", "fence", "chain", "kerb", "cycle_barrier", "turnstile", "unknown"}) {
    EXPECT_TRUE(blocks(b)) << b;
  }
  for (const char* b : {"gate", "lift_gate", "toll_booth", "border_control", "cattle_grid", "entrance", "no", ""}) {
    EXPECT_FALSE(blocks(b)) << b;
  }
  EXPECT_FALSE(blocks("bollard", "bollard", "rising"));
  EXPECT_FALSE(blocks("bollard", "bollard", "removable"));
  EXPECT_TRUE(blocks("bollard", "bollard", "fixed"));
  EXPECT_FALSE(blocks("kerb", "kerb", "flush"));
  EXPECT_TRUE(blocks("kerb", "kerb", "raised"));
  EXPECT_TRUE(blocks("gate", "access", "no"));
  EXPECT_FALSE(blocks("gate", "access", "private"));  // private does not stop an emergency vehicle
  EXPECT_FALSE(blocks("block", "emergency", "yes"));
  // A height restrictor becomes a limit on its roads, which the vehicle profile checks.
  EXPECT_FALSE(blocks("height_restrictor"));
  EXPECT_FALSE(blocks("height_restrictor", "maxheight", "2.5"));
}

// The barriers a vehicle passes but stops at: every kind of gate, toll booths, border posts and
// bollards someone must lower. Not those it drives over, and not those that block it.
TEST(NodeRules, BarriersTheVehicleStopsAt) {
  auto stops = [](auto... tags) { return node_stops_vehicle(barrier_node(tags...)); };
  for (const char* b : {"gate", "lift_gate", "swing_gate", "sliding_gate", "bump_gate", "sally_port", "toll_booth", "border_control"}) {
    EXPECT_TRUE(stops(b)) << b;
  }
  for (const char* b : {"cattle_grid", "entrance", "arch", "no", "", "height_restrictor"}) EXPECT_FALSE(stops(b)) << b;
  for (const char* b : {"rising", "removable", "retractable", "foldable"}) EXPECT_TRUE(stops("bollard", "bollard", b)) << b;
  EXPECT_FALSE(stops("bollard", "bollard", "flexible"));  // driven over
  EXPECT_FALSE(stops("bollard"));                         // blocks: no route passes it
  EXPECT_FALSE(stops("gate", "access", "no"));            // blocks
  EXPECT_TRUE(stops("gate", "access", "private"));
  EXPECT_FALSE(stops("gate", "access", "yes"));  // open to everyone: it stands open
  EXPECT_FALSE(stops("lift_gate", "access", "permissive"));
  EXPECT_TRUE(stops("toll_booth", "access", "yes"));
  for (const char* b : {"bollard", "block", "chain"}) EXPECT_TRUE(stops(b, "emergency", "yes")) << b;  // only for it
  NodeTags opened = barrier_node("gate", "access", "no");  // with emergency=yes: it passes, and waits for it to open
  opened.emergency = "yes";
  EXPECT_TRUE(node_stops_vehicle(opened));
}

TEST(WayRules, PhysicalLimitsAreReadNotJudged) {
  WayTags t;
  t.highway = "residential";
  t.maxheight = "3.2 m";
  t.maxwidth = "2.2";
  t.maxweight = "7500 kg";
  const auto r = interpret_way(t);
  ASSERT_TRUE(r.has_value());
  EXPECT_DOUBLE_EQ(r->max_height_m, 3.2);
  EXPECT_DOUBLE_EQ(r->max_width_m, 2.2);
  EXPECT_DOUBLE_EQ(r->max_weight_t, 7.5);
  t.maxheight = "default";
  t.maxwidth = "none";
  t.maxweight = "heavy";
  const auto none = interpret_way(t);
  EXPECT_EQ(none->max_height_m, 0.0);
  EXPECT_EQ(none->max_width_m, 0.0);
  EXPECT_EQ(none->max_weight_t, 0.0);
  EXPECT_NEAR(*parse_length_m("9'6\""), 2.8956, 1e-9);
  EXPECT_NEAR(*parse_length_m("12 ft"), 3.6576, 1e-9);
  EXPECT_NEAR(*parse_weight_t("10 st"), 9.0718474, 1e-9);
  EXPECT_DOUBLE_EQ(*parse_weight_t("15"), 15.0);
  EXPECT_FALSE(parse_weight_t("15 stone").has_value());
  EXPECT_FALSE(parse_length_m("-3").has_value());
}

}  // namespace
// Ferries as OSRM's car profile reads them: route=ferry|shuttle_train with or without a highway
// tag, the same access rules, no implied oneway, and the crossing's pace rather than a limit.
TEST(WayRules, FerriesAndShuttleTrains) {
  WayTags ferry;
  ferry.route = "ferry";
  auto rules = interpret_way(ferry);
  ASSERT_TRUE(rules.has_value());
  EXPECT_EQ(rules->road_class, RoadClass::ferry);
  EXPECT_TRUE(rules->forward && rules->backward);
  EXPECT_DOUBLE_EQ(rules->forward_speed_kmh, 5.0);
  EXPECT_DOUBLE_EQ(rules->duration_s, 0.0);
  ferry.duration = "1:30";
  ferry.maxspeed = "50";  // a speed limit does not make a boat faster
  rules = interpret_way(ferry);
  ASSERT_TRUE(rules.has_value());
  EXPECT_DOUBLE_EQ(rules->duration_s, 5400.0);
  EXPECT_DOUBLE_EQ(rules->forward_speed_kmh, 5.0);
  ferry.oneway = "yes";
  EXPECT_FALSE(interpret_way(ferry)->backward);
  ferry.oneway = {};
  ferry.motor_vehicle = "no";  // a foot ferry
  EXPECT_FALSE(interpret_way(ferry).has_value());

  WayTags train;
  train.route = "shuttle_train";
  rules = interpret_way(train);
  ASSERT_TRUE(rules.has_value());
  EXPECT_EQ(rules->road_class, RoadClass::ferry);
  EXPECT_DOUBLE_EQ(rules->forward_speed_kmh, 10.0);
  for (const char* other : {"ferry_man", "bus", "road", "hiking"}) {
    WayTags t;
    t.route = other;
    EXPECT_FALSE(interpret_way(t).has_value()) << other;
  }
  // A road that is also a ferry route rides the ferry.
  WayTags both = road("primary");
  both.route = "ferry";
  EXPECT_EQ(interpret_way(both)->road_class, RoadClass::ferry);
  EXPECT_EQ(to_string(RoadClass::ferry), "ferry");
  EXPECT_FALSE(road_class_from_highway("ferry").has_value());
}

TEST(DurationParsing, ClockIsoAndMinutes) {
  EXPECT_DOUBLE_EQ(*parse_duration_s("0:01"), 60.0);
  EXPECT_DOUBLE_EQ(*parse_duration_s("96:00"), 345600.0);
  EXPECT_DOUBLE_EQ(*parse_duration_s("1:02:03"), 3723.0);
  EXPECT_DOUBLE_EQ(*parse_duration_s("45"), 2700.0);
  EXPECT_DOUBLE_EQ(*parse_duration_s("PT1H30M"), 5400.0);
  EXPECT_DOUBLE_EQ(*parse_duration_s("P1DT2H"), 93600.0);
  EXPECT_DOUBLE_EQ(*parse_duration_s(" pt45s "), 45.0);
  for (const char* bad : {"", "0:00", "abc", "1:2:3:4", "1:", "PT", "P1H", "PT1X", "-1:00", "1h", "1:nan", "1e40", "PT1e-40S",
                          "inf", "P400D"}) {
    EXPECT_FALSE(parse_duration_s(bad).has_value()) << bad;
  }
}

}  // namespace corridor::maps
