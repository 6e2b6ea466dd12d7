// Odometry map matching (Parra Alonso §IV) and the GPS/odometry switch on HDOP, on a crossroads.
#include <gtest/gtest.h>

#include "localizer/fusion/gps_odometry_localizer.hpp"
#include "tests/localizer/sketch_graph.hpp"

namespace corridor::localizer {
namespace {

using testing::Sketch;

// A crossroads at (0,0) with arms 300 m long to the north (1), east (2), south (3) and west (4).
maps::RoadGraph crossroads() {
  Sketch s;
  s.nodes = {{0, 0}, {0, 300}, {300, 0}, {0, -300}, {-300, 0}};
  s.roads = {{{4, 0, 2}, false, 1}, {{1, 0, 3}, false, 2}};
  return s.build();
}

EdgeId edge_between(const maps::RoadGraph& g, maps::Point2 from, maps::Point2 to) {
  for (EdgeId e : g.edges()) {
    if (maps::distance_m(g.position(g.tail(e)), from) < 1.0 && maps::distance_m(g.position(g.head(e)), to) < 1.0) return e;
  }
  return EdgeId{};
}

// Drives 10 m a second from 150 m west of the junction, eastbound; `turn_deg` is spread over the
// 20 m around the junction. Returns the edge after 150 m more.
std::pair<EdgeId, const OdometryMapMatcher*> drive(const maps::RoadGraph& g, OdometryMapMatcher& m, double turn_deg) {
  const EdgeId west_in = edge_between(g, {-300, 0}, {0, 0});
  m.start(west_in, 150.0, 90.0, 0.0, 5.0);
  double t = 0.0, driven = 0.0;
  MatchedPoint p;
  for (int i = 0; i < 30; ++i) {
    t += 1.0;
    const double before = driven;
    driven += 10.0;
    // The share of the turn made in this step: the heading changes between 140 and 160 m.
    const double overlap = std::max(0.0, std::min(driven, 160.0) - std::max(before, 140.0));
    p = m.advance({t, 10.0, turn_deg * overlap / 20.0});
  }
  return {p.edge, &m};
}

TEST(OdometryMapMatcher, GoesStraightThroughAJunctionWithoutATurn) {
  const auto g = crossroads();
  OdometryMapMatcher m(g);
  EXPECT_EQ(drive(g, m, 0.0).first, edge_between(g, {0, 0}, {300, 0}));
  EXPECT_EQ(m.resets(), 0u);
  // 300 m driven at 1 % drift: the uncertainty grew from 5 m.
  EXPECT_NEAR(m.sigma_m(), 5.0 + 0.01 * 300.0, 0.5);
}

TEST(OdometryMapMatcher, TakesTheExitItsHeadingTurnedToAndResetsTheDrift) {
  const auto g = crossroads();
  OdometryMapMatcher right(g);
  EXPECT_EQ(drive(g, right, 90.0).first, edge_between(g, {0, 0}, {0, -300}));  // east, then south
  EXPECT_EQ(right.resets(), 1u);
  OdometryMapMatcher left(g);
  EXPECT_EQ(drive(g, left, -90.0).first, edge_between(g, {0, 0}, {0, 300}));
  EXPECT_EQ(left.resets(), 1u);
  // The sharp turn put the vehicle back on the map: the uncertainty restarted from the base and
  // grew only over the metres since.
  EXPECT_LT(left.sigma_m(), 5.0);
}

TEST(OdometryMapMatcher, AHeadingThatDisagreesWithTheRoadRaisesTheUncertainty) {
  const auto g = crossroads();
  OdometryMapMatcher m(g);
  m.start(edge_between(g, {-300, 0}, {0, 0}), 10.0, 90.0, 0.0, 5.0);
  for (int i = 1; i <= 4; ++i) m.advance({static_cast<double>(i), 1.0, 0.0});
  const double agreeing = m.sigma_m();
  m.advance({5.0, 1.0, 35.0});  // the odometry now says 125° on a road that runs at 90°
  for (int i = 6; i <= 12; ++i) m.advance({static_cast<double>(i), 1.0, 0.0});
  EXPECT_GT(m.sigma_m(), agreeing * 1.2);
}

TEST(GpsOdometryLocalizer, SwitchesToOdometryOnPoorGpsAndBackWithoutAJump) {
  const auto g = crossroads();
  const maps::EdgeSnapper snapper(g);
  GpsOdometryLocalizer loc(g, snapper);
  auto fix = [&](double t, double x, double hdop) {
    GpsFix f;
    f.time_s = t;
    f.position = g.projection().to_lat_lon({x, 1.0});
    f.hdop = hdop;
    f.heading_deg = 90.0;
    f.speed_mps = 10.0;
    return f;
  };
  double x = -280.0;
  LocalizedPoint p;
  for (int t = 0; t < 10; ++t, x += 10.0) {
    if (t > 0) loc.on_odometry({static_cast<double>(t), 10.0, 0.0});
    p = loc.on_gps(fix(t, x, 1.0));
  }
  ASSERT_EQ(p.source, PositionSource::gps);
  const maps::Point2 last_gps = p.match.point;
  // GPS degrades (HDOP 15): fixes are ignored, odometry carries on from the last good one.
  std::vector<LocalizedPoint> during;
  for (int t = 10; t < 20; ++t, x += 10.0) {
    loc.on_odometry({static_cast<double>(t), 10.0, 0.0});
    during.push_back(loc.on_gps(fix(t, x + 80.0, 15.0)));  // the bad fixes are 80 m off
  }
  // Within the timeout the last GPS point stands; then odometry, continuing from it.
  EXPECT_EQ(during[0].source, PositionSource::gps);
  EXPECT_EQ(during.back().source, PositionSource::odometry);
  const auto first_odometry = std::find_if(during.begin(), during.end(), [](const auto& q) { return q.source == PositionSource::odometry; });
  ASSERT_NE(first_odometry, during.end());
  const double handover_gap = maps::distance_m(first_odometry->match.point, last_gps);
  EXPECT_LT(handover_gap, 10.0 * static_cast<double>(first_odometry - during.begin() + 1) + 1.0);  // no jump beyond driving
  EXPECT_NEAR(during.back().match.point.x_m, x - 10.0, 5.0);  // where the vehicle really is
  // GPS is good again: followed, and the position moves by the odometry's small error only.
  loc.on_odometry({20.0, 10.0, 0.0});
  const LocalizedPoint back = loc.on_gps(fix(20.0, x, 1.0));
  EXPECT_EQ(back.source, PositionSource::gps);
  EXPECT_LT(maps::distance_m(back.match.point, during.back().match.point), 15.0);
}

}  // namespace
}  // namespace corridor::localizer
