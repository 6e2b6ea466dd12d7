// The odometry's scale, calibrated against the receiver's speed, and what it does for an outage.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "localizer/fusion/gps_odometry_localizer.hpp"
#include "localizer/fusion/odometry_scale.hpp"
#include "tests/localizer/sketch_graph.hpp"

namespace corridor::localizer {
namespace {

// 1 Hz fixes of a vehicle whose speed wanders between 6 and 14 m/s, with the receiver's speed
// noise (0.3 m/s), and an odometry that reports `scale` times the distance driven. Each call
// drives on from where the last one stopped.
struct Drive {
  double time_s = 0, odometry_m = 0, v = 10.0;
  std::mt19937_64 rng{7};
  std::normal_distribution<double> noise{0.0, 0.3};
  void calibrate(OdometryScale& s, double scale, int fixes) {
    for (int k = 0; k < fixes; ++k) {
      const double v_next = 10.0 + 4.0 * std::sin(0.05 * (time_s + 1.0));
      if (time_s > 0.0) odometry_m += scale * 0.5 * (v + v_next);  // the distance driven, as the odometry reports it
      v = v_next;
      s.on_fix(time_s, v + noise(rng), odometry_m);
      time_s += 1.0;
    }
  }
};

TEST(OdometryScale, LearnsTheScaleFromTheReceiversSpeed) {
  for (const double scale : {0.97, 1.0, 1.02}) {
    OdometryScale s;
    Drive().calibrate(s, scale, 400);
    EXPECT_NEAR(s.factor() * scale, 1.0, 0.002) << "odometry scale " << scale;
    EXPECT_GT(s.calibrated_m(), 300.0);
  }
}

TEST(OdometryScale, StaysOneUntilEnoughHasBeenDriven) {
  OdometryScale s;
  Drive d;
  d.calibrate(s, 1.03, 25);  // about 260 m of odometry
  EXPECT_LT(s.calibrated_m(), 300.0);
  EXPECT_EQ(s.factor(), 1.0);
  d.calibrate(s, 1.03, 60);
  EXPECT_GT(s.calibrated_m(), 300.0);
  EXPECT_NEAR(s.factor(), 1.0 / 1.03, 0.01);
}

// A clock that goes back (a replay started over) starts the next interval afresh: the calibration
// goes on rather than waiting for time to pass the old maximum.
TEST(OdometryScale, AClockThatGoesBackStartsAfresh) {
  OdometryScale s;
  Drive d;
  d.calibrate(s, 1.03, 20);
  d.time_s = 0.0;
  d.calibrate(s, 1.03, 60);
  EXPECT_GT(s.calibrated_m(), 700.0);
  EXPECT_NEAR(s.factor(), 1.0 / 1.03, 0.01);
}

TEST(OdometryScale, WithoutSpeedsTheOdometryStandsAsReported) {
  OdometryScale s;
  for (int k = 0; k < 200; ++k) s.on_fix(k, std::nullopt, 13.0 * k);
  EXPECT_EQ(s.factor(), 1.0);
  EXPECT_EQ(s.calibrated_m(), 0.0);
}

// A stop: a receiver's speed at rest is noise, and an odometry that creeps while the speed reads
// 1 m/s must not count. A gap in the fixes and an interval where the two disagree by half
// (a speed spike, a VO glitch) do not count either.
TEST(OdometryScale, StopsGapsAndImplausibleIntervalsDoNotCount) {
  OdometryScale s;
  double odometry_m = 0.0;
  for (int k = 0; k < 100; ++k) s.on_fix(k, 1.0, odometry_m += 2.0);  // slow: skipped
  EXPECT_EQ(s.calibrated_m(), 0.0);
  s.on_fix(100, 10.0, odometry_m);
  s.on_fix(105, 10.0, odometry_m += 50.0);  // a 5 s gap
  EXPECT_EQ(s.calibrated_m(), 0.0);
  s.on_fix(106, 10.0, odometry_m += 15.0);  // 50 % off
  EXPECT_EQ(s.calibrated_m(), 0.0);
  for (int k = 107; k < 160; ++k) s.on_fix(k, 10.0, odometry_m += 10.0);
  // 53 intervals of 10 m, each older one faded by the next's 10 m over the 3 km memory.
  const double q = std::exp(-10.0 / 3000.0);
  EXPECT_NEAR(s.calibrated_m(), 10.0 * (1.0 - std::pow(q, 53)) / (1.0 - q), 1e-6);
  EXPECT_DOUBLE_EQ(s.factor(), 1.0);
}

TEST(OdometryScale, TheCorrectionIsBounded) {
  OdometryScale s;
  Drive().calibrate(s, 1.15, 400);
  EXPECT_DOUBLE_EQ(s.factor(), 0.95);
}

// A vehicle drives a straight road east at 12 m/s with good GPS for 100 s, then GPS goes for
// 60 s. Its odometry reports 4 % too much: uncorrected, the odometry puts it 29 m ahead by the
// outage's end; calibrated against the receiver's speed before the outage, within a few metres.
double along_error_after_outage(bool calibrate_scale) {
  const maps::RoadGraph g = testing::straight_road(3000.0);
  const maps::EdgeSnapper snapper(g);
  LocalizerConfig config;
  config.odometry_scale.enabled = calibrate_scale;
  GpsOdometryLocalizer loc(g, snapper, config);
  std::mt19937_64 rng(5);
  std::normal_distribution<double> noise(0.0, 1.0);
  double x = 100.0;
  LocalizedPoint p;
  for (int t = 0; t <= 160; ++t) {
    if (t > 0) {
      x += 12.0;
      p = loc.on_odometry({static_cast<double>(t), 12.0 * 1.04, 0.0});
    }
    if (t <= 100) {
      GpsFix f;
      f.time_s = t;
      f.position = g.projection().to_lat_lon({x + 3.0 * noise(rng), 3.0 * noise(rng)});
      f.hdop = 0.75;
      f.heading_deg = 90.0 + 2.0 * noise(rng);
      f.speed_mps = 12.0 + 0.3 * noise(rng);
      p = loc.on_gps(f);
    }
  }
  EXPECT_EQ(p.source, PositionSource::odometry);
  return p.match.point.x_m - x;
}

TEST(GpsOdometryLocalizer, AnOutageIsDrivenOnTheScaleTheReceiversSpeedCalibrated) {
  EXPECT_GT(along_error_after_outage(false), 20.0);
  EXPECT_LT(std::abs(along_error_after_outage(true)), 5.0);
}

}  // namespace
}  // namespace corridor::localizer
