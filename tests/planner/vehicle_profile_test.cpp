#include "planner/vehicle_profile.hpp"

#include <gtest/gtest.h>

#include "planner/travel_cost.hpp"
#include "tests/planner/test_graphs_line.hpp"

namespace corridor::planner {
namespace {

const std::filesystem::path kProfiles = std::filesystem::path(CORRIDOR_SOURCE_DIR) / "planner" / "profiles";

TEST(VehicleProfile, ShippedFilesAreTheBuiltInProfiles) {
  EXPECT_EQ(profile_to_json(load_profile(kProfiles / "ambulance.json")), profile_to_json(ambulance_profile()));
  EXPECT_EQ(profile_to_json(load_profile(kProfiles / "fire_engine.json")), profile_to_json(fire_engine_profile()));
  EXPECT_EQ(builtin_profile("fire_engine").height_m, 3.5);
  EXPECT_THROW(builtin_profile("tank"), ProfileError);
}

TEST(VehicleProfile, JsonOverridesABase) {
  const auto p = profile_from_json(R"({"base": "fire_engine", "name": "ladder", "height_m": 3.9, "uturn": "anywhere",
                                       "restriction_modes": ["all", "hgv"], "speed_factor": {"residential": 0.7}})");
  EXPECT_EQ(p.name, "ladder");
  EXPECT_EQ(p.height_m, 3.9);
  EXPECT_EQ(p.weight_t, 15.0);  // from the base
  EXPECT_EQ(p.uturn_policy, UturnPolicy::anywhere);
  EXPECT_EQ(p.restriction_modes, maps::mode_bit(maps::RestrictionMode::all) | maps::mode_bit(maps::RestrictionMode::hgv));
  EXPECT_EQ(p.speed_factor[static_cast<std::size_t>(maps::RoadClass::residential)], 0.7);
  EXPECT_TRUE(p.ferries);
  EXPECT_FALSE(profile_from_json(R"({"ferries": false})").ferries);
  // The JSON written back reads as the same profile.
  EXPECT_EQ(profile_to_json(profile_from_json(profile_to_json(p))), profile_to_json(p));
}

// The message a profile JSON is rejected with, or "accepted".
std::string error_of(const char* json) {
  try {
    (void)profile_from_json(json);
  } catch (const ProfileError& e) {
    return std::string(e.what());
  }
  return std::string("accepted");
}

TEST(VehicleProfile, BadJsonIsAClearError) {
  EXPECT_NE(error_of("{").find("not valid JSON"), std::string::npos);
  EXPECT_NE(error_of(R"({"height_m": 1e4444})").find("not valid JSON"), std::string::npos);  // overflows a double
  EXPECT_NE(error_of("[]").find("object"), std::string::npos);
  EXPECT_NE(error_of(R"({"height": 3})").find("unknown key 'height'"), std::string::npos);
  EXPECT_NE(error_of(R"({"height_m": "tall"})").find("'height_m' must be a number"), std::string::npos);
  EXPECT_NE(error_of(R"({"height_m": -1})").find("height_m"), std::string::npos);
  EXPECT_NE(error_of(R"({"vmax_kmh": 0})").find("vmax"), std::string::npos);
  EXPECT_NE(error_of(R"({"uturn": "sometimes"})").find("uturn"), std::string::npos);
  EXPECT_NE(error_of(R"({"restriction_modes": ["tram"]})").find("unknown restriction mode"), std::string::npos);
  EXPECT_NE(error_of(R"({"speed_factor": {"residential": 1.5}})").find("(0, 1]"), std::string::npos);
  EXPECT_NE(error_of(R"({"speed_factor": {"lane": 0.5}})").find("unknown road class"), std::string::npos);
  EXPECT_NE(error_of(R"({"base": "tank"})").find("unknown vehicle profile"), std::string::npos);
  EXPECT_NE(error_of(R"({"ferries": "sometimes"})").find("'ferries' must be true or false"), std::string::npos);
  EXPECT_NE(error_of(R"({"barrier_delay_s": -5})").find("barrier_delay_s must be in [0, 3600]"), std::string::npos);
  EXPECT_NE(error_of(R"({"barrier_delay_s": 7200})").find("barrier_delay_s"), std::string::npos);
  EXPECT_DOUBLE_EQ(profile_from_json(R"({"barrier_delay_s": 0})").barrier_delay_s, 0.0);
  EXPECT_THROW((void)load_profile("/nonexistent/profile.json"), ProfileError);
}

TEST(VehicleProfile, ExceptClassesFromJson) {
  using maps::class_bit;
  using maps::VehicleClass;
  EXPECT_EQ(profile_from_json(R"({"except_classes": ["hgv", "emergency"]})").except_classes,
            class_bit(VehicleClass::hgv) | class_bit(VehicleClass::emergency));
  EXPECT_EQ(profile_from_json(R"({"except_classes": []})").except_classes, 0);
  // The older key: false lifts nothing (true keeps the base's classes, which name emergency and psv).
  EXPECT_EQ(profile_from_json(R"({"emergency_exceptions": false})").except_classes, 0);
  EXPECT_NE(error_of(R"({"except_classes": ["bus"]})").find("unknown vehicle class \"bus\""), std::string::npos);
  EXPECT_NE(error_of(R"({"except_classes": "hgv"})").find("array"), std::string::npos);
  EXPECT_NE(error_of(R"({"except_classes": [], "emergency_exceptions": true})").find("not both"), std::string::npos);
}

TEST(VehicleProfile, SpeedFactorSlowsItsRoadClassOnly) {
  const auto g = testing::diamond();  // residential roads
  const EdgeId ab = testing::edge_from_to(g, 1, 2);
  ASSERT_EQ(g.road_class(ab), maps::RoadClass::residential);
  const CostOverlay overlay(g);
  VehicleProfile p;
  p.vmax_mps = 30.0;
  EXPECT_DOUBLE_EQ(TravelCost(g, overlay, p).running_time_s(ab), 10.0);
  p.speed_factor[static_cast<std::size_t>(maps::RoadClass::motorway)] = 0.5;
  EXPECT_DOUBLE_EQ(TravelCost(g, overlay, p).running_time_s(ab), 10.0);
  p.speed_factor[static_cast<std::size_t>(maps::RoadClass::residential)] = 0.5;
  EXPECT_DOUBLE_EQ(TravelCost(g, overlay, p).running_time_s(ab), 20.0);
}

}  // namespace
}  // namespace corridor::planner
