#include "sim/sumo_signal_controller.hpp"

#include <gtest/gtest.h>

#include <map>

namespace corridor::sim {
namespace {

// A stand-in for one SUMO traffic light: runs its static program, or shows what it is told.
class FakeLights final : public TrafficLightApi {
 public:
  explicit FakeLights(std::vector<maps::SumoTlPhase> phases) : phases_(std::move(phases)) {}

  void advance(double now_s) {
    while (program_ && now_s - phase_start_ >= phases_[static_cast<std::size_t>(phase_)].duration_s) {
      phase_start_ += phases_[static_cast<std::size_t>(phase_)].duration_s;
      phase_ = (phase_ + 1) % static_cast<int>(phases_.size());
    }
    now_ = now_s;
  }
  std::string state(const std::string&) override { return program_ ? phases_[static_cast<std::size_t>(phase_)].state : online_; }
  int phase(const std::string&) override { return phase_; }
  double spent_s(const std::string&) override { return now_ - phase_start_; }
  void set_state(const std::string&, const std::string& state) override {
    program_ = false;
    online_ = state;
    history.emplace_back(now_, state);
  }
  void set_program(const std::string&, const std::string& id) override {
    program_ = true;
    restored_program = id;
  }
  void set_phase(const std::string&, int phase) override {
    phase_ = phase;
    phase_start_ = now_;
    history.emplace_back(now_, "program@" + std::to_string(phase));
  }

  std::vector<std::pair<double, std::string>> history;
  std::string restored_program;
  [[nodiscard]] bool on_program() const { return program_; }

 private:
  std::vector<maps::SumoTlPhase> phases_;
  int phase_ = 0;
  double phase_start_ = 0.0;
  double now_ = 0.0;
  bool program_ = true;
  std::string online_;
};

// Links 0, 1 north-south; links 2, 3 east-west; each pair conflicts with the other.
struct Fixture {
  Fixture() {
    maps::SignalPlan& p = plans[node];
    p.node = node;
    p.movements.resize(4);
    p.conflict.assign(16, 0);
    for (int a : {0, 1}) {
      for (int b : {2, 3}) p.conflict[static_cast<std::size_t>(a * 4 + b)] = p.conflict[static_cast<std::size_t>(b * 4 + a)] = 1;
    }
    p.phases = {{"GGrr", {1, 1, 0, 0}, 5.0}, {"rrGG", {0, 0, 1, 1}, 5.0}};
    p.program = {{0, 30.0}, {1, 30.0}};
    p.yellow_s = 3.0;
    p.all_red_s = 2.0;
    sumo.tls_id = "J";
    sumo.program_id = "0";
    sumo_of[node] = &sumo;
    phases["J"] = {{30.0, "GGrr", 0.0}, {3.0, "yyrr", 0.0}, {30.0, "rrGG", 0.0}, {3.0, "rryy", 0.0}};
  }
  NodeId node{7};
  std::unordered_map<NodeId, maps::SignalPlan> plans;
  maps::SumoSignalPlan sumo;
  std::unordered_map<NodeId, const maps::SumoSignalPlan*> sumo_of;
  std::unordered_map<std::string, std::vector<maps::SumoTlPhase>> phases;
};

void run(FakeLights& api, SumoSignalController& c, double from_s, double to_s) {
  for (double t = from_s; t <= to_s + 1e-9; t += 0.5) {
    api.advance(t);
    c.update(t);
  }
}

TEST(SumoSignalController, HoldGoesThroughYellowAndAllRedThenReleaseRestoresTheProgram) {
  Fixture f;
  FakeLights api(f.phases["J"]);
  SumoSignalController c(f.plans, f.sumo_of, f.phases, api);
  run(api, c, 0.0, 10.0);
  EXPECT_EQ(c.current_phase(f.node), 0u);
  c.hold(f.node, f.plans[f.node].phases[1], 10.0);
  EXPECT_EQ(c.mode(f.node), preemption::SignalMode::held);
  run(api, c, 10.5, 40.0);
  const std::vector<std::pair<double, std::string>> expected_hold{{10.0, "yyrr"}, {13.0, "rrrr"}, {15.0, "rrGG"}};
  ASSERT_GE(api.history.size(), 3u);
  EXPECT_EQ(std::vector(api.history.begin(), api.history.begin() + 3), expected_hold);
  EXPECT_EQ(c.holds_reached(), 1u);
  EXPECT_EQ(c.current_phase(f.node), 1u);
  EXPECT_EQ(c.green_start_s(f.node, 2), 15.0);

  c.release(f.node, 0, 40.0);
  run(api, c, 40.5, 50.0);
  const std::vector<std::pair<double, std::string>> expected_all{
      {10.0, "yyrr"}, {13.0, "rrrr"}, {15.0, "rrGG"}, {40.0, "rryy"}, {43.0, "rrrr"}, {45.0, "program@0"}};
  EXPECT_EQ(api.history, expected_all);
  EXPECT_EQ(api.restored_program, "0");
  EXPECT_TRUE(api.on_program());
  EXPECT_EQ(c.mode(f.node), preemption::SignalMode::program);
  EXPECT_EQ(c.lights_taken_over(), 1u);
  EXPECT_EQ(c.lights_on_program(), 1u);
  EXPECT_EQ(c.programs_restored(), 1u);
  EXPECT_TRUE(c.violations().empty()) << c.violations().front();
}

TEST(SumoSignalController, HoldWaitsForTheProgramsMinimumGreen) {
  Fixture f;
  FakeLights api(f.phases["J"]);
  SumoSignalController c(f.plans, f.sumo_of, f.phases, api);
  run(api, c, 0.0, 1.0);
  EXPECT_NEAR(c.remaining_min_green_s(f.node, 1.0), 4.0, 1e-9);
  c.hold(f.node, f.plans[f.node].phases[1], 1.0);
  run(api, c, 1.5, 12.0);
  ASSERT_FALSE(api.history.empty());
  EXPECT_EQ(api.history.front(), (std::pair<double, std::string>{5.0, "yyrr"}));
  EXPECT_TRUE(c.violations().empty());
}

TEST(SumoSignalController, HoldOfThePhaseOnShowNeedsNoClearance) {
  Fixture f;
  FakeLights api(f.phases["J"]);
  SumoSignalController c(f.plans, f.sumo_of, f.phases, api);
  run(api, c, 0.0, 10.0);
  c.hold(f.node, f.plans[f.node].phases[0], 10.0);
  run(api, c, 10.5, 12.0);
  ASSERT_FALSE(api.history.empty());
  EXPECT_EQ(api.history.front(), (std::pair<double, std::string>{10.0, "GGrr"}));
  EXPECT_TRUE(c.violations().empty());
}

TEST(SumoSignalController, ReleaseDuringClearanceGoesBackToTheProgramWithoutShowingTheHold) {
  Fixture f;
  FakeLights api(f.phases["J"]);
  SumoSignalController c(f.plans, f.sumo_of, f.phases, api);
  run(api, c, 0.0, 10.0);
  c.hold(f.node, f.plans[f.node].phases[1], 10.0);
  run(api, c, 10.5, 11.0);
  c.release(f.node, 1, 11.0);
  run(api, c, 11.5, 20.0);
  for (const auto& [t, state] : api.history) EXPECT_NE(state, "rrGG") << "at " << t;
  EXPECT_EQ(api.history.back(), (std::pair<double, std::string>{15.0, "program@2"}));  // step 1 = SUMO phase 2
  EXPECT_EQ(c.mode(f.node), preemption::SignalMode::program);
  EXPECT_TRUE(c.violations().empty());
}

TEST(SumoSignalController, ChangingTheHeldPhaseClearsTheOldGreenFirst) {
  Fixture f;
  FakeLights api(f.phases["J"]);
  SumoSignalController c(f.plans, f.sumo_of, f.phases, api);
  run(api, c, 0.0, 10.0);
  c.hold(f.node, f.plans[f.node].phases[1], 10.0);
  run(api, c, 10.5, 30.0);
  c.hold(f.node, f.plans[f.node].phases[0], 30.0);
  run(api, c, 30.5, 40.0);
  const std::vector<std::pair<double, std::string>> expected{{10.0, "yyrr"}, {13.0, "rrrr"}, {15.0, "rrGG"},
                                                             {30.0, "rryy"}, {33.0, "rrrr"}, {35.0, "GGrr"}};
  EXPECT_EQ(api.history, expected);
  EXPECT_TRUE(c.violations().empty());
}

// A new held phase asked for while the clearance towards the first is running: a link the first
// kept green and the second drops still gets its yellow and all-red before the second's green
// (found in the Fig. 11 matrix, where a light went from green to red without yellow).
TEST(SumoSignalController, ChangingTheTargetDuringTheClearanceStillClearsWhatItDrops) {
  Fixture f;
  FakeLights api(f.phases["J"]);
  SumoSignalController c(f.plans, f.sumo_of, f.phases, api);
  run(api, c, 0.0, 10.0);
  c.hold(f.node, maps::Phase{"Grrr", {1, 0, 0, 0}, 5.0}, 10.0);
  run(api, c, 10.5, 12.0);
  c.hold(f.node, f.plans[f.node].phases[1], 12.0);
  run(api, c, 12.5, 30.0);
  const std::vector<std::pair<double, std::string>> expected{{10.0, "Gyrr"}, {13.0, "Grrr"}, {15.0, "yrrr"},
                                                             {18.0, "rrrr"}, {20.0, "rrGG"}};
  EXPECT_EQ(api.history, expected);
  EXPECT_TRUE(c.violations().empty()) << c.violations().front();
}

// A new held phase asked for during the all-red before the held green: the all-red still runs in
// full before anything turns green.
TEST(SumoSignalController, ChangingTheTargetDuringTheAllRedKeepsTheAllRed) {
  Fixture f;
  FakeLights api(f.phases["J"]);
  SumoSignalController c(f.plans, f.sumo_of, f.phases, api);
  run(api, c, 0.0, 10.0);
  c.hold(f.node, f.plans[f.node].phases[1], 10.0);  // GGrr -> yyrr (10) -> rrrr (13) -> rrGG (15)
  run(api, c, 10.5, 13.5);
  c.hold(f.node, maps::Phase{"rrGr", {0, 0, 1, 0}, 5.0}, 13.5);
  run(api, c, 14.0, 20.0);
  const std::vector<std::pair<double, std::string>> expected{{10.0, "yyrr"}, {13.0, "rrrr"}, {15.0, "rrGr"}};
  EXPECT_EQ(api.history, expected);
  EXPECT_TRUE(c.violations().empty()) << c.violations().front();
}

// What SUMO's program will show, from its phase on show: a fixed program phase by phase, an
// actuated one only as far as the shortest the phase on show can be; nothing while held.
TEST(SumoSignalController, ForecastsAFixedProgramAndOnlyTheShortestActuatedPhase) {
  Fixture f;
  FakeLights api(f.phases["J"]);
  SumoSignalController c(f.plans, f.sumo_of, f.phases, api);
  api.advance(10.0);
  const auto forecast = c.program_forecast(f.node, 10.0, 100.0);
  ASSERT_GE(forecast.size(), 4u);
  EXPECT_DOUBLE_EQ(forecast[0].start_s, 10.0);
  EXPECT_DOUBLE_EQ(forecast[0].end_s, 30.0);
  EXPECT_EQ(forecast[0].green, (std::vector<std::uint8_t>{1, 1, 0, 0}));
  EXPECT_FALSE(forecast[0].clearance);
  EXPECT_DOUBLE_EQ(forecast[0].min_green_end_s, 5.0);  // the phase began at 0 s
  EXPECT_TRUE(forecast[1].clearance);
  EXPECT_DOUBLE_EQ(forecast[1].end_s, 33.0);
  EXPECT_EQ(forecast[2].green, (std::vector<std::uint8_t>{0, 0, 1, 1}));
  EXPECT_DOUBLE_EQ(forecast[2].end_s, 63.0);
  EXPECT_GE(forecast.back().end_s, 110.0);
  c.hold(f.node, f.plans[f.node].phases[1], 10.0);
  EXPECT_TRUE(c.program_forecast(f.node, 10.0, 100.0).empty());

  auto phases = f.phases;
  phases["J"][0].min_duration_s = 12.0;
  FakeLights actuated_api(phases["J"]);
  SumoSignalController actuated(f.plans, f.sumo_of, phases, actuated_api, {"J"});
  actuated_api.advance(10.0);
  const auto short_forecast = actuated.program_forecast(f.node, 10.0, 100.0);
  ASSERT_EQ(short_forecast.size(), 1u);
  EXPECT_DOUBLE_EQ(short_forecast[0].end_s, 12.0);
}

TEST(SumoSignalController, RejectsAPlanWithoutItsLight) {
  Fixture f;
  FakeLights api(f.phases["J"]);
  const std::unordered_map<NodeId, const maps::SumoSignalPlan*> none;
  EXPECT_THROW(SumoSignalController(f.plans, none, f.phases, api), std::runtime_error);
}

}  // namespace
}  // namespace corridor::sim
