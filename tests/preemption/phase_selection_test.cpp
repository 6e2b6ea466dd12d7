#include "preemption/phase_selection.hpp"

#include <gtest/gtest.h>

#include <random>

namespace corridor::preemption {
namespace {

using maps::Compass;

TEST(NemaPlan, MovementNumbersAndPhasesFollowThePaper) {
  const auto plan = maps::make_nema_plan(NodeId{1});
  ASSERT_EQ(plan.movements.size(), 12u);
  ASSERT_EQ(plan.phases.size(), 8u);
  EXPECT_EQ(maps::nema_movement(Compass::north, maps::Turn::through), 4);
  EXPECT_EQ(maps::nema_movement(Compass::north, maps::Turn::left), 7);
  EXPECT_EQ(maps::nema_movement(Compass::south, maps::Turn::right), 8);
  EXPECT_EQ(maps::nema_movement(Compass::south, maps::Turn::left), 3);
  EXPECT_EQ(maps::nema_movement(Compass::west, maps::Turn::through), 2);
  EXPECT_EQ(maps::nema_movement(Compass::west, maps::Turn::left), 5);
  EXPECT_EQ(maps::nema_movement(Compass::east, maps::Turn::through), 6);
  EXPECT_EQ(maps::nema_movement(Compass::east, maps::Turn::left), 1);
  EXPECT_EQ(plan.phases[plan.program.front().phase].label, "4+7");  // the cycle starts with 4+7
  for (const auto& phase : plan.phases) EXPECT_TRUE(plan.phase_is_safe(phase)) << phase.label;
  // North through and South left may never be green together.
  EXPECT_TRUE(plan.conflicts(*plan.movement_index(Compass::north, Compass::south), *plan.movement_index(Compass::south, Compass::west)));
  EXPECT_FALSE(plan.conflicts(*plan.movement_index(Compass::north, Compass::south), *plan.movement_index(Compass::south, Compass::north)));
  // Every movement gets green somewhere in the normal cycle.
  for (std::size_t m = 0; m < plan.movements.size(); ++m) {
    bool served = false;
    for (const auto& step : plan.program) served = served || plan.phases[step.phase].serves(m);
    EXPECT_TRUE(served) << plan.movements[m].label();
  }
}

TEST(NemaPlan, ThreeLeggedJunctionDegrades) {
  // No East leg: no movements from or to the East, and phases 1+5, 1+6... keep what is left.
  const auto plan = maps::make_nema_plan(NodeId{1}, 0b1101);
  EXPECT_EQ(plan.movements.size(), 6u);
  for (const auto& m : plan.movements) {
    EXPECT_NE(m.from, Compass::east);
    EXPECT_NE(m.to, Compass::east);
  }
  for (const auto& phase : plan.phases) EXPECT_TRUE(plan.phase_is_safe(phase));
  EXPECT_FALSE(plan.program.empty());
  for (std::size_t m = 0; m < plan.movements.size(); ++m) {
    bool served = false;
    for (const auto& step : plan.program) served = served || plan.phases[step.phase].serves(m);
    EXPECT_TRUE(served) << plan.movements[m].label();
  }
}

TEST(PhaseSelection, TablesAgreeInExactlyOneEighthOfTheCells) {
  const DecisionTables t = nema_decision_tables();
  ASSERT_EQ(t.movements.size(), 12u);
  ASSERT_EQ(t.phases.size(), 8u);
  int agree = 0;
  for (std::size_t m = 0; m < 12; ++m) {
    for (std::size_t p = 0; p < 8; ++p) agree += t.high[m][p] == t.low[m][p] ? 1 : 0;
  }
  EXPECT_EQ(agree * 8, 96);
}

TEST(PhaseSelection, PaperWorkedExampleNorthToSouthUnderThreePlusEight) {
  const DecisionTables t = nema_decision_tables();
  const auto row = std::find(t.movements.begin(), t.movements.end(), "N->S") - t.movements.begin();
  const auto col = std::find(t.phases.begin(), t.phases.end(), "3+8") - t.phases.begin();
  EXPECT_EQ(t.low[row][col], "4+8");
  EXPECT_EQ(t.high[row][col], "4+7");
}

TEST(PhaseSelection, HighCongestionGivesTheWholeApproach) {
  const auto plan = maps::make_nema_plan(NodeId{1});
  const std::pair<Compass, const char*> expected[] = {
      {Compass::north, "4+7"}, {Compass::south, "3+8"}, {Compass::west, "2+5"}, {Compass::east, "1+6"}};
  for (const auto& [from, label] : expected) {
    for (std::size_t m = 0; m < plan.movements.size(); ++m) {
      if (plan.movements[m].from != from) continue;
      for (std::size_t p = 0; p < plan.phases.size(); ++p) {
        const auto d = select_phase(plan, m, p, CongestionLevel::high);
        EXPECT_EQ(d.phase.label, label);
        EXPECT_EQ(d.extend, plan.phases[p].label == label);
      }
    }
  }
}

// A hand-made plan where the vehicle's movement (N->S) is served by two phases that both serve
// another approach: P0 with S->N, P1 with W->N. Detector demand decides; without it, the tie goes
// to plan order.
TEST(PhaseSelection, LowCongestionFollowsMeasuredDemand) {
  maps::SignalPlan plan;
  plan.node = NodeId{9};
  plan.movements = {{Compass::north, Compass::south, maps::Turn::through, 0},
                    {Compass::south, Compass::north, maps::Turn::through, 0},
                    {Compass::west, Compass::north, maps::Turn::right, 0},
                    {Compass::east, Compass::west, maps::Turn::through, 0}};
  plan.conflict = {0, 0, 0, 1,  //
                   0, 0, 1, 1,  //
                   0, 1, 0, 1,  //
                   1, 1, 1, 0};
  plan.phases = {{"P0", {1, 1, 0, 0}, 5.0}, {"P1", {1, 0, 1, 0}, 5.0}, {"P2", {0, 0, 0, 1}, 5.0}};
  plan.program = {{0, 20.0}, {1, 20.0}, {2, 20.0}};
  EXPECT_EQ(select_phase(plan, 0, 2, CongestionLevel::low).phase.label, "P0");
  std::vector<double> demand{std::nan(""), 1.0, 10.0, std::nan("")};
  EXPECT_EQ(select_phase(plan, 0, 2, CongestionLevel::low, demand).phase.label, "P1");
  demand = {std::nan(""), 10.0, 1.0, std::nan("")};
  EXPECT_EQ(select_phase(plan, 0, 2, CongestionLevel::low, demand).phase.label, "P0");
  // Already served: extend, whatever the demand.
  const auto keep = select_phase(plan, 0, 1, CongestionLevel::low, demand);
  EXPECT_EQ(keep.phase.label, "P1");
  EXPECT_TRUE(keep.extend);
}

// A plan whose phases never give the vehicle's movement green: a phase is built from the conflict
// relation, and it is safe.
TEST(PhaseSelection, SynthesizesASafePhaseWhenNoPhaseServesTheMovement) {
  auto plan = maps::make_nema_plan(NodeId{1});
  const std::size_t n_e = *plan.movement_index(Compass::north, Compass::east);
  for (auto& phase : plan.phases) phase.green[n_e] = 0;  // the North left is never served
  const auto d = select_phase(plan, n_e, 0, CongestionLevel::low);
  EXPECT_FALSE(d.index.has_value());
  EXPECT_TRUE(d.phase.serves(n_e));
  EXPECT_TRUE(plan.phase_is_safe(d.phase));
  EXPECT_TRUE(d.phase.serves(*plan.movement_index(Compass::north, Compass::south)));  // its approach too
}

TEST(PhaseSelection, SynthesizedPhaseAlsoServesOtherApproachesThatConflictWithNothingGreen) {
  // North-south and east-west throughs; the program never serves north-south.
  maps::SignalPlan plan;
  plan.movements = {{Compass::north, Compass::south}, {Compass::south, Compass::north},
                    {Compass::east, Compass::west}, {Compass::west, Compass::east}};
  plan.conflict.assign(16, 0);
  for (std::size_t a : {0u, 1u}) {
    for (std::size_t b : {2u, 3u}) plan.conflict[a * 4 + b] = plan.conflict[b * 4 + a] = 1;
  }
  plan.phases = {{"EW", {0, 0, 1, 1}, 5.0}};
  plan.program = {{0, 30.0}};
  const auto d = select_phase(plan, 0, 0, CongestionLevel::low);
  EXPECT_FALSE(d.index.has_value());
  EXPECT_TRUE(plan.phase_is_safe(d.phase));
  EXPECT_EQ(d.phase.green, (std::vector<std::uint8_t>{1, 1, 0, 0}));  // the opposite through runs too
}

}  // namespace
}  // namespace corridor::preemption
