#include "preemption/timing.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "preemption/congestion_classifier.hpp"
#include "preemption/queue_estimator.hpp"

namespace corridor::preemption {
namespace {

// Vehicle due at the stop line at τ = 60 s; the current phase owes 2 s of min green; yellow 3 s,
// all-red 2 s, safety margin 3 s: Trans = 2 + 3 + 2 = 7 s and p = 60 − 7 − 3 = 50 s.
TEST(PreemptionTiming, StartWithoutCongestionIsArrivalMinusTransitionMinusMargin) {
  TimingConfig c;
  c.safety_margin_s = 3.0;
  const double trans = transition_time_s(2.0, 3.0, 2.0);
  EXPECT_DOUBLE_EQ(trans, 7.0);
  EXPECT_DOUBLE_EQ(preemption_start_s(60.0, trans, 0.0, c), 50.0);
  EXPECT_DOUBLE_EQ(transition_time_s(-4.0, 3.0, 2.0), 5.0);  // min green already served
}

// Green on since t_G0 = 20 s with D(t_G0) = 10; A(τ) = 40 vehicles by τ = 60 s; s = 0.5 veh/s:
// n_q = 40 − 10 − 0.5 × (60 − 20) = 10 vehicles; t_q = l1 + h·n = 2 + 2 × 10 = 22 s;
// p = 60 − 7 − 3 − 22 = 28 s.
TEST(PreemptionTiming, StartWithQueueWhileGreenIsOn) {
  TimingConfig c;
  c.safety_margin_s = 3.0;
  c.startup_lost_time_s = 2.0;
  c.saturation_headway_s = 2.0;
  c.saturation_flow_vps = 0.5;
  QueueInputs q;
  q.green_on = true;
  q.green_start_s = 20.0;
  q.departures_at_green_start = 10.0;
  q.arrivals_at_tau = 40.0;
  const double n = queue_at_arrival_veh(60.0, q, c);
  EXPECT_DOUBLE_EQ(n, 10.0);
  const double tq = queue_clearance_s(n, c);
  EXPECT_DOUBLE_EQ(tq, 22.0);
  EXPECT_DOUBLE_EQ(preemption_start_s(60.0, 7.0, tq, c), 28.0);
  // A green long enough to discharge everything leaves no queue (never negative).
  q.arrivals_at_tau = 25.0;
  EXPECT_DOUBLE_EQ(queue_at_arrival_veh(60.0, q, c), 0.0);
}

// Red on the approach: n_q = A(τ) − D(t_G0 + g) = 31 − 18 = 13; t_q = 2 + 2 × 13 = 28 s.
TEST(PreemptionTiming, QueueWhileRedCountsArrivalsSinceTheLastGreenEnded) {
  TimingConfig c;
  QueueInputs q;
  q.green_on = false;
  q.arrivals_at_tau = 31.0;
  q.departures_at_green_end = 18.0;
  EXPECT_DOUBLE_EQ(queue_at_arrival_veh(45.0, q, c), 13.0);
  EXPECT_DOUBLE_EQ(queue_clearance_s(13.0, c), 28.0);
}

TEST(QueueEstimator, CumulativeCountsRatesAndProjection) {
  QueueEstimator q;
  EXPECT_FALSE(q.has_data(maps::Compass::north));
  q.record(maps::Compass::north, 0.0, 0.0, 0.0);
  q.record(maps::Compass::north, 10.0, 5.0, 2.0);  // 0.5 veh/s arriving
  EXPECT_TRUE(q.has_data(maps::Compass::north));
  EXPECT_DOUBLE_EQ(q.queue_now(maps::Compass::north), 3.0);
  EXPECT_DOUBLE_EQ(q.arrival_rate_vps(maps::Compass::north), 0.5);
  EXPECT_DOUBLE_EQ(q.arrivals_at(maps::Compass::north, 30.0), 5.0 + 0.5 * 20.0);
  EXPECT_DOUBLE_EQ(q.departures_at(maps::Compass::north, 5.0), 1.0);  // interpolated
  EXPECT_DOUBLE_EQ(q.departures_at(maps::Compass::north, 50.0), 2.0);
  EXPECT_FALSE(q.has_data(maps::Compass::south));
}

TEST(QueueEstimator, RejectsBadCounts) {
  QueueEstimator q;
  q.record(maps::Compass::east, 10.0, 1.0, 1.0);
  EXPECT_THROW(q.record(maps::Compass::east, 5.0, 1.0, 1.0), CountError);  // back in time
  EXPECT_THROW(q.record(maps::Compass::east, 20.0, -1.0, 0.0), CountError);
  EXPECT_THROW(q.record(maps::Compass::east, 20.0, std::nan(""), 0.0), CountError);
  EXPECT_DOUBLE_EQ(q.queue_now(maps::Compass::east), 0.0);  // nothing stored by the rejected calls
}

TEST(CongestionClassifier, UsesQueueThenOccupancyThenSpeed) {
  const CongestionClassifierConfig c;  // queue >= 6, occupancy >= 0.3, speed ratio <= 0.5
  EXPECT_EQ(classify_congestion({}, c), CongestionLevel::low);
  EXPECT_EQ(classify_congestion({6.0, std::nullopt, std::nullopt, std::nullopt}, c), CongestionLevel::high);
  EXPECT_EQ(classify_congestion({2.0, 0.9, 0.1, std::nullopt}, c), CongestionLevel::low);  // the queue decides first
  EXPECT_EQ(classify_congestion({std::nullopt, 0.35, std::nullopt, std::nullopt}, c), CongestionLevel::high);
  EXPECT_EQ(classify_congestion({std::nullopt, std::nullopt, 0.4, std::nullopt}, c), CongestionLevel::high);
  EXPECT_EQ(classify_congestion({std::nullopt, std::nullopt, 0.8, std::nullopt}, c), CongestionLevel::low);
}

}  // namespace
}  // namespace corridor::preemption
