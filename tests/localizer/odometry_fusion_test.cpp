// Odometry map matching (Parra Alonso §IV) and the GPS/odometry switch on HDOP, on a crossroads.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <optional>
#include <vector>

#include "localizer/fusion/gps_odometry_localizer.hpp"
#include "tests/localizer/sketch_graph.hpp"

namespace corridor::localizer {
namespace {

using testing::Sketch;
using testing::edge_between;

// A crossroads at (0,0) with arms 300 m long to the north (1), east (2), south (3) and west (4).
maps::RoadGraph crossroads() {
  Sketch s;
  s.nodes = {{0, 0}, {0, 300}, {300, 0}, {0, -300}, {-300, 0}};
  s.roads = {{{4, 0, 2}, false, 1}, {{1, 0, 3}, false, 2}};
  return s.build();
}

// The localizer on the crossroads, for the tests of its GPS side.
class LocalizerOnCrossroads : public ::testing::Test {
 protected:
  maps::RoadGraph g = crossroads();
  maps::EdgeSnapper snapper{g};
  GpsOdometryLocalizer loc{g, snapper};
  LocalizedPoint p;

  // Drives east from 250 m west of the junction at 10 m/s for `seconds`: odometry at 10 Hz, a
  // fix a second (course and speed given). Returns where the vehicle is.
  double drive_east(int seconds);
};

// A fix 1 m north of the east-west road, at x metres east of the crossroads.
GpsFix fix_at(const maps::RoadGraph& g, double t, double x, std::optional<double> hdop) {
  GpsFix f;
  f.time_s = t;
  f.position = g.projection().to_lat_lon({x, 1.0});
  f.hdop = hdop;
  return f;
}

double LocalizerOnCrossroads::drive_east(int seconds) {
  double x = -250.0;
  for (int k = 0; k <= 10 * seconds; ++k) {
    const double t = 0.1 * k;
    if (k > 0) {
      x += 1.0;
      p = loc.on_odometry({t, 1.0, 0.0});
    }
    if (k % 10 == 0) {
      GpsFix f = fix_at(g, t, x, 1.0);
      f.heading_deg = 90.0;
      f.speed_mps = 10.0;
      p = loc.on_gps(f);
    }
  }
  return x;
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

// Eastbound towards the crossroads, the vehicle slows to a stop that the odometry puts 0.2 m past
// the node (its front is at the stop line, right by the node in the map). It must stay on its
// approach while it waits, not be reported on an exit past the junction it waits at. When it
// drives on, it takes the exit with the distance it was held back carried, not lost.
TEST(OdometryMapMatcher, AVehicleStoppingRightAtTheNodeWaitsOnItsApproach) {
  const auto g = crossroads();
  const EdgeId west_in = edge_between(g, {-300, 0}, {0, 0}), east_out = edge_between(g, {0, 0}, {300, 0});
  OdometryMapMatcher m(g);
  m.start(west_in, 250.0, 90.0, 0.0, 5.0);
  double t = 0.0;
  MatchedPoint p;
  for (const double d : {8.0, 8.0, 8.0, 8.0, 8.0, 5.0, 3.0, 1.5, 0.7}) p = m.advance({t += 1.0, d, 0.0});
  for (int i = 0; i < 30; ++i) {
    p = m.advance({t += 1.0, 0.0, 0.0});
    ASSERT_EQ(p.edge, west_in) << "standing, second " << i;
    EXPECT_NEAR(p.offset_m, 300.0, 1e-9);
  }
  p = m.advance({t += 1.0, 10.0, 0.0});
  EXPECT_EQ(p.edge, east_out);
  EXPECT_NEAR(p.offset_m, 10.2, 0.01);
  // A vehicle that passes the node at speed is not held back, however little of the step is left.
  OdometryMapMatcher fast(g);
  fast.start(west_in, 270.5, 90.0, 0.0, 5.0);
  t = 0.0;
  for (int i = 0; i < 3; ++i) p = fast.advance({t += 1.0, 10.0, 0.0});
  EXPECT_EQ(p.edge, east_out);
  EXPECT_NEAR(p.offset_m, 0.5, 0.01);
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


// A fork of two streets 4° apart (north-east of the junction at 88° and 92°): 150 m on, the left
// one bends to 45°, the right one runs on. The vehicle takes the left one, but its odometry's
// heading is 5° off from the start (a GPS course's error), so at the fork it points down the
// right one. One committed exit stays on the wrong street; the hypotheses keep both until the
// bend tells them apart.
TEST(OdometryMapMatcher, KeepsBothStreetsOfANarrowForkUntilTheyPart) {
  Sketch s;
  const double r = 3.14159265358979 / 180.0;
  auto at = [&](double bearing_deg, double from_x, double from_y, double len) {
    return maps::Point2{from_x + len * std::sin(bearing_deg * r), from_y + len * std::cos(bearing_deg * r)};
  };
  const maps::Point2 left_bend = at(88.0, 0, 0, 150.0);
  const maps::Point2 left_end = at(45.0, left_bend.x_m, left_bend.y_m, 200.0);
  const maps::Point2 right_mid = at(92.0, 0, 0, 150.0);
  const maps::Point2 right_end = at(92.0, 0, 0, 350.0);
  s.nodes = {{-200, 0}, {0, 0}, left_bend, left_end, right_mid, right_end};
  s.roads = {{{0, 1}, false, 1}, {{1, 2, 3}, false, 2}, {{1, 4, 5}, false, 3}};
  const auto g = s.build();
  OdometryMapMatcher m(g);
  m.start(edge_between(g, {-200, 0}, {0, 0}), 195.0, 95.0, 0.0, 5.0);  // truly 90°, 5 m before the fork
  MatchedPoint p;
  double driven = 0.0;
  for (int t = 1; t <= 30; ++t) {
    driven += 10.0;
    double turn = 0.0;
    if (driven <= 10.0) turn = -2.0;                      // onto the left street (90° -> 88°)
    if (driven > 155.0 && driven <= 175.0) turn = -21.5;  // its bend, over 20 m
    p = m.advance({static_cast<double>(t), 10.0, turn});
  }
  ASSERT_TRUE(p.matched);
  EXPECT_EQ(p.edge, edge_between(g, left_bend, left_end));
  EXPECT_LT(maps::distance_m(p.point, at(45.0, left_bend.x_m, left_bend.y_m, 135.0)), 15.0);
}

// The odometry reads 2% short (a scale error), so along a 300 m street the position falls 6 m
// behind. A 40° bend is too gentle for the drift reset, but the hypotheses put out siblings ahead
// and behind, and the bend picks one that fits better: 100 m past it (2 m more of drift), the
// position is 5 m short instead of 8.
TEST(OdometryMapMatcher, ABendTakesOutTheAlongRoadDrift) {
  Sketch s;
  const double r = 3.14159265358979 / 180.0;
  const maps::Point2 bend{300, 0};
  const maps::Point2 end{300 + 200 * std::sin(130 * r), 200 * std::cos(130 * r)};
  s.nodes = {{0, 0}, bend, end};
  s.roads = {{{0, 1}, false, 1}, {{1, 2}, false, 2}};
  const auto g = s.build();
  OdometryMatchConfig config;
  config.corner = {0.0, 0.0};  // this vehicle drives the centre lines, bend and all
  OdometryMapMatcher m(g, config);
  m.start(edge_between(g, {0, 0}, bend), 0.0, 90.0, 0.0, 3.0);
  MatchedPoint p;
  double truly = 0.0;
  for (int t = 1; t <= 200; ++t) {  // 2 m steps, as a visual odometry at 10 Hz gives them
    const double before = truly;
    truly += 2.0;
    // The 40° turn is made over the 10 m from 295 to 305 m (truly driven).
    const double turn = 40.0 * std::max(0.0, std::min(truly, 305.0) - std::max(before, 295.0)) / 10.0;
    p = m.advance({0.2 * t, 2.0 * 0.98, turn});
  }
  ASSERT_TRUE(p.matched);
  const maps::Point2 truth{bend.x_m + 100 * std::sin(130 * r), bend.y_m + 100 * std::cos(130 * r)};
  EXPECT_EQ(p.edge, edge_between(g, bend, end));
  EXPECT_LT(maps::distance_m(p.point, truth), 5.5);  // 8 m short without the siblings
}

// A fork whose one-way branches part by 25° at (0, 100); 100 m on, the left one (A) bends away
// to the north-west while the right one (B) runs on. The vehicle took B and is 28 m down it when
// GPS goes; the online match put it on A, and the fixes' mean lies 15.6 m from A but 27.3 m from
// B, outside the confidence region's 25 m. The other exits of the node behind the match start
// too, as far past it: where A bends and the odometry runs on straight, B wins.
TEST(OdometryMapMatcher, TheOtherBranchOfAForkJustPassedStartsToo) {
  Sketch s;
  const double pi = 3.14159265358979, half = 12.5 * pi / 180.0, away = -55.0 * pi / 180.0;
  const maps::Point2 bend{-100 * std::sin(half), 100 + 100 * std::cos(half)};
  s.nodes = {{0, 0}, {0, 100}, bend, {bend.x_m + 300 * std::sin(away), bend.y_m + 300 * std::cos(away)},
             {400 * std::sin(half), 100 + 400 * std::cos(half)}};
  s.roads = {{{0, 1}, true, 1}, {{1, 2, 3}, true, 2}, {{1, 4}, true, 3}};
  const auto g = s.build();
  const maps::EdgeSnapper snapper(g);
  OdometryMapMatcher m(g, {}, &snapper);
  const EdgeId a = edge_between(g, s.nodes[1], bend), b = edge_between(g, s.nodes[1], s.nodes[4]);
  OdometryStart from;
  from.edge = a;
  from.offset_m = 27.0;
  from.point = {-22.0, 127.0};
  from.heading_deg = 12.5;
  from.heading_sigma_deg = 20.0;
  from.sigma_m = 10.0;
  m.start(from);
  MatchedPoint p;
  for (int t = 1; t <= 20; ++t) p = m.advance({static_cast<double>(t), 10.0, 0.0});
  EXPECT_EQ(p.edge, b);
  EXPECT_NEAR(p.offset_m, 228.0, 10.0);
}

// An octagon of two-way road (sides 61 m), driven clockwise: five right turns of 45°, each
// rounded on an 8 m arc 1.75 m right of the centre line, so the vehicle drives 1.72 m less than
// the centre lines at each (corner_cut.hpp). The odometry measures the arcs exactly; the
// hypotheses move along the centre lines and must add what each corner saved, else they fall
// behind: 8.6 m, of which the siblings' search along the road wins back 6. (45° is below the
// sharp-turn reset.)
double octagon_along_error(const CornerModel& corner) {
  Sketch s;
  const double pi = 3.14159265358979, radius = 80.0;
  for (int k = 0; k < 8; ++k) s.nodes.push_back({radius * std::cos(-k * pi / 4), radius * std::sin(-k * pi / 4)});
  s.roads = {{{0, 1, 2, 3, 4, 5, 6, 7, 0}, false, 1}};
  const auto g = s.build();
  const double side = maps::distance_m(s.nodes[0], s.nodes[1]);
  const double theta = pi / 4, tangent = 8.0 * std::tan(theta / 2), arc = (8.0 - 1.75) * theta;
  OdometryMatchConfig config;
  config.corner = corner;
  OdometryMapMatcher m(g, config);
  const EdgeId first = edge_between(g, s.nodes[0], s.nodes[1]);
  const double first_bearing = std::atan2(s.nodes[1].x_m - s.nodes[0].x_m, s.nodes[1].y_m - s.nodes[0].y_m) * 180.0 / pi;
  m.start(first, 20.0, first_bearing, 0.0, 3.0);
  // The driven path: straight to the first arc, then (arc, straight) five times, ending half-way
  // along the straight after the fifth corner.
  std::vector<std::pair<double, double>> pieces{{side - tangent - 20.0, 0.0}};  // (length, turn over it)
  for (int k = 0; k < 5; ++k) pieces.push_back({arc, 45.0}), pieces.push_back({k < 4 ? side - 2 * tangent : (side - 2 * tangent) / 2, 0.0});
  MatchedPoint p;
  double t = 0.0;
  for (const auto& [length, turn] : pieces) {
    const int steps = static_cast<int>(std::ceil(length / 2.0));
    for (int i = 0; i < steps; ++i) p = m.advance({t += 0.2, length / steps, turn / steps});
  }
  EXPECT_TRUE(p.matched);
  EXPECT_EQ(p.edge, edge_between(g, s.nodes[5], s.nodes[6]));
  return p.offset_m - side / 2;
}

TEST(OdometryMapMatcher, AHypothesisAddsWhatEachCornerSavedTheVehicle) {
  EXPECT_LT(std::abs(octagon_along_error({})), 0.5);
  EXPECT_LT(octagon_along_error({0.0, 0.0}), -2.0);
}

// Two ways meet 10 m after a sharp turn (a node where nothing turns): the turn still resets the
// drift.
TEST(OdometryMapMatcher, ANodeRightAfterASharpTurnDoesNotHideIt) {
  Sketch s;
  s.nodes = {{-300, 0}, {0, 0}, {300, 0}, {0, -10}, {0, -300}};
  s.roads = {{{0, 1, 2}, false, 1}, {{1, 3}, false, 2}, {{3, 4}, false, 3}};
  const auto g = s.build();
  OdometryMapMatcher m(g);
  EXPECT_EQ(drive(g, m, 90.0).first, edge_between(g, {0, -10}, {0, -300}));
  EXPECT_EQ(m.resets(), 1u);
}

// A fix with HDOP 0 (a receiver's placeholder) or none at all still gives a finite position,
// and the odometry that starts from it stays finite.
TEST_F(LocalizerOnCrossroads, AZeroHdopIsTheDefaultNotADivisionByZero) {
  for (int t = 0; t < 5; ++t) {
    if (t > 0) loc.on_odometry({static_cast<double>(t), 10.0, 0.0});
    p = loc.on_gps(fix_at(g, t, -200.0 + 10.0 * t, t % 2 == 0 ? 0.0 : std::numeric_limits<double>::quiet_NaN()));
    ASSERT_TRUE(std::isfinite(p.match.offset_m) && std::isfinite(p.match.point.x_m)) << "fix " << t;
  }
  for (int t = 5; t < 12; ++t) p = loc.on_odometry({static_cast<double>(t), 10.0, 0.0});
  ASSERT_EQ(p.source, PositionSource::odometry);
  EXPECT_NEAR(p.match.point.x_m, -200.0 + 10.0 * 11, 5.0);
}

// GPS alone, no odometry: the averaging along the road must not hold a moving vehicle back at
// where its older fixes were.
TEST_F(LocalizerOnCrossroads, WithoutOdometryAMovingVehicleIsNotHeldBack) {
  for (int t = 0; t < 10; ++t) {
    p = loc.on_gps(fix_at(g, t, -250.0 + 15.0 * t, 2.0));  // σ 8 m: older fixes would count if nothing carried them
  }
  EXPECT_NEAR(p.match.point.x_m, -250.0 + 15.0 * 9, 1.0);
}

// A stopped vehicle's heading came from the road alone, and the road ran the other way: the
// hypothesis facing back lives on, and wins when the vehicle turns where only it can.
TEST(OdometryMapMatcher, AVehicleFacingTheOtherWayIsFoundByItsTurn) {
  Sketch s;
  // West-east road from (-200,0) to (0,0); at its east end a road north, at its west end a road
  // north too: eastbound that is a left turn, westbound a right turn.
  s.nodes = {{-200, 0}, {0, 0}, {0, 200}, {-200, 200}};
  s.roads = {{{0, 1}, false, 1}, {{1, 2}, false, 2}, {{0, 3}, false, 3}};
  const auto g = s.build();
  OdometryMapMatcher m(g);
  OdometryStart from;
  from.edge = edge_between(g, {-200, 0}, {0, 0});
  from.offset_m = 100.0;
  from.point = {-100, 0};
  from.heading_deg = 90.0;         // the road's eastbound bearing...
  from.heading_sigma_deg = 45.0;   // ...and nothing better known
  m.start(from);
  MatchedPoint p;
  double driven = 0.0;
  for (int t = 1; t <= 20; ++t) {
    driven += 10.0;
    const double turn = driven > 95.0 && driven <= 115.0 ? 45.0 : 0.0;  // a right turn, 100 m on
    p = m.advance({static_cast<double>(t), 10.0, turn});
  }
  ASSERT_TRUE(p.matched);
  EXPECT_EQ(p.edge, edge_between(g, {-200, 0}, {-200, 200}));
}

// A vehicle stopped 100 m west of the crossroads: its fixes scatter along the road by ±8 m, and
// the localizer's position along the road is their mean, not the last one.
TEST_F(LocalizerOnCrossroads, AveragesAStoppedVehiclesFixesAlongTheRoad) {
  const double scatter[] = {8.0, -6.0, 5.0, -7.0, 6.0, -4.0, 7.0, -8.0, 4.0, 6.0};
  for (int t = 0; t < 10; ++t) {
    if (t > 0) loc.on_odometry({static_cast<double>(t), 0.0, 0.0});
    p = loc.on_gps(fix_at(g, t, -100.0 + scatter[t], 1.5));
  }
  ASSERT_EQ(p.source, PositionSource::gps);
  EXPECT_LT(std::abs(p.match.point.x_m - (-100.0)), 2.0);  // the last fix alone is 6 m off
}

// Parallel east-west roads, 800 m long, at the given y (the first at 0), joined by a short
// north-south street at x = link_x: the online match can cross between them there.
maps::RoadGraph parallel_roads(const std::vector<double>& ys, double link_x) {
  Sketch s;
  std::vector<std::uint32_t> link;
  for (std::size_t i = 0; i < ys.size(); ++i) {
    const auto first = static_cast<std::uint32_t>(s.nodes.size());
    s.nodes.insert(s.nodes.end(), {{-400, ys[i]}, {link_x, ys[i]}, {400, ys[i]}});
    s.roads.push_back({{first, first + 1, first + 2}, false, static_cast<std::int64_t>(i + 1)});
    link.push_back(first + 1);
  }
  s.roads.push_back({link, false, 99});
  return s.build();
}

// Eastbound at 10 m/s on the road y = 0, with odometry each second; fix t at (x0 + 10 t, y(t)).
struct ParallelDrive {
  maps::RoadGraph g;
  maps::EdgeSnapper snapper{g};
  GpsOdometryLocalizer loc{g, snapper};
  ParallelDrive(const std::vector<double>& ys, double link_x) : g(parallel_roads(ys, link_x)) {}
  LocalizedPoint fix(int t, double y, bool with_course = true) {
    if (t > 0) loc.on_odometry({static_cast<double>(t), 10.0, 0.0});
    GpsFix f;
    f.time_s = t;
    f.position = g.projection().to_lat_lon({-300.0 + 10.0 * t, y});
    f.hdop = 1.0;
    if (with_course) {
      f.heading_deg = 90.0;
      f.speed_mps = 10.0;
    }
    return loc.on_gps(f);
  }
  LocalizedPoint outage(int from_t, int to_t) {
    LocalizedPoint p;
    for (int t = from_t; t <= to_t; ++t) p = loc.on_odometry({static_cast<double>(t), 10.0, 0.0});
    return p;
  }
};

// The last fix before GPS goes quiet is a multipath jump onto a road 60 m off, and the online
// match follows it (nothing after it says otherwise). The odometry does not restart from it: it
// fails the gate against the fixes before it, carried by the odometry, so the outage is driven on
// the true road. Averaged in, it would pull the start 11 m north, almost onto a street 12 m away.
TEST(GpsOdometryLocalizer, AMultipathFixJustBeforeAnOutageIsNotWhereTheOdometryStarts) {
  ParallelDrive d({0.0, 12.0, 60.0}, -205.0);
  for (int t = 0; t < 10; ++t) d.fix(t, 0.0);
  const LocalizedPoint jumped = d.fix(10, 60.0);
  ASSERT_EQ(jumped.source, PositionSource::gps);
  EXPECT_GT(jumped.match.point.y_m, 50.0);  // shown as GPS gave it...
  const LocalizedPoint p = d.outage(11, 20);
  ASSERT_EQ(p.source, PositionSource::odometry);
  EXPECT_LT(std::abs(p.match.point.y_m), 1.0);  // ...but the odometry drives on the true road
  EXPECT_NEAR(p.match.point.x_m, -300.0 + 10.0 * 20, 5.0);
}

// The fixes move to the other road and stay there (the vehicle is there; the earlier fixes were
// wrong): the first is gated, the second agrees with it, and the odometry restarts from them.
TEST(GpsOdometryLocalizer, TwoFixesThatAgreeOverruleTheFixesBeforeThem) {
  ParallelDrive d({0.0, 60.0}, -205.0);
  for (int t = 0; t < 10; ++t) d.fix(t, 1.0);
  d.fix(10, 60.0);
  d.fix(11, 61.0);
  const LocalizedPoint p = d.outage(12, 20);
  ASSERT_EQ(p.source, PositionSource::odometry);
  EXPECT_NEAR(p.match.point.y_m, 60.0, 1.0);
}

// After ten good fixes, multipath only: fixes alternate between roads 60 m north and south,
// every one gated. The odometry takes over 1.5 s after the last good fix and stays the output;
// the gated fixes do not flip it back to GPS each second.
TEST(GpsOdometryLocalizer, GatedFixesDoNotFlipTheOdometryBackToGps) {
  ParallelDrive d({-60.0, 0.0, 60.0}, -150.0);
  for (int t = 0; t < 10; ++t) d.fix(t, 0.0);
  LocalizedPoint p;
  for (int t = 10; t < 20; ++t) {
    p = d.fix(t, t % 2 == 0 ? 60.0 : -60.0);
    if (t >= 12) {
      ASSERT_EQ(p.source, PositionSource::odometry) << "t = " << t;
      EXPECT_LT(std::abs(p.match.point.y_m), 1.0) << "t = " << t;
    }
  }
}

// Two roads 14 m apart. The fixes scatter around the road y = 0 (σ 4 m), and the last one, 11 m
// north, is nearer the other road: the online match takes that one. The odometry starts from the
// fixes' mean, carried by the odometry, not from the last match, and drives the outage on y = 0.
TEST(GpsOdometryLocalizer, TheOdometryStartsFromTheFixesMeanNotTheLastMatch) {
  ParallelDrive d({0.0, 14.0}, -212.0);
  const double y[] = {3.0, -4.0, 2.0, -3.0, 4.0, -2.0, 3.0, -4.0, 1.0, 11.0};
  LocalizedPoint last;
  for (int t = 0; t < 10; ++t) last = d.fix(t, y[t]);
  ASSERT_GT(last.match.point.y_m, 13.0);  // the online match is on the other road
  const LocalizedPoint p = d.outage(10, 16);
  ASSERT_EQ(p.source, PositionSource::odometry);
  EXPECT_LT(std::abs(p.match.point.y_m), 1.0);
}

// A receiver that gives no course: once the vehicle moves, its fixes cannot be carried, so there
// is no mean, and the odometry starts from the online match (the road y = 0), not from the last
// raw fix, which lies 7.5 m north, nearer the road 14 m away than its own.
TEST(GpsOdometryLocalizer, WithoutACourseTheOdometryStartsFromTheMatchNotTheRawFix) {
  ParallelDrive d({0.0, 14.0}, 100.0);
  LocalizedPoint last;
  for (int t = 0; t < 10; ++t) last = d.fix(t, t < 9 ? 1.0 : 7.5, false);
  ASSERT_LT(std::abs(last.match.point.y_m), 1.0);  // the online match stays on y = 0
  const LocalizedPoint p = d.outage(10, 16);
  ASSERT_EQ(p.source, PositionSource::odometry);
  EXPECT_LT(std::abs(p.match.point.y_m), 1.0);
}

// A 10 Hz receiver whose fixes arrive 0.2 s late, odometry at 20 Hz: the odometry does not take
// over between two of its fixes (1.5 of its intervals is 0.15 s; the floor is 1 s).
TEST_F(LocalizerOnCrossroads, AFastReceiversLatencyDoesNotHandOverBetweenItsFixes) {
  int odometry_outputs = 0;
  for (int k = 1; k <= 200; ++k) {
    const double t = 0.05 * k;
    p = loc.on_odometry({t, 0.5, 0.0});
    if (k > 40) odometry_outputs += p.source == PositionSource::odometry ? 1 : 0;
    if (k % 2 == 0 && k >= 4) {  // the fix of 0.2 s ago
      GpsFix f = fix_at(g, t - 0.2, -250.0 + 10.0 * (t - 0.2), 1.0);
      f.heading_deg = 90.0;
      f.speed_mps = 10.0;
      p = loc.on_gps(f);
    }
  }
  EXPECT_EQ(odometry_outputs, 0);
}

// A 1 Hz receiver, odometry at 10 Hz. When a fix does not come, the odometry takes over once one
// and a half of the fixes' intervals have passed (not after the 2.5 s timeout): the source says
// so, and the position is where the vehicle drove to.
TEST_F(LocalizerOnCrossroads, AnOverdueFixHandsOverToTheOdometrySoonerThanTheTimeout) {
  const double x = drive_east(10);
  ASSERT_EQ(p.source, PositionSource::gps);  // the last fix, at t = 10 s
  for (int k = 101; k <= 114; ++k) p = loc.on_odometry({0.1 * k, 1.0, 0.0});
  EXPECT_EQ(p.source, PositionSource::gps) << "1.4 s after the fix: it may still come";
  for (int k = 115; k <= 120; ++k) p = loc.on_odometry({0.1 * k, 1.0, 0.0});
  ASSERT_EQ(p.source, PositionSource::odometry) << "2 s after it: overdue";
  EXPECT_NEAR(p.match.point.x_m, x + 20.0, 3.0);
}

// A 1 Hz receiver and a 10 Hz odometry: between two fixes the position moves on with the
// odometry from the last fix (still GPS's, dead-reckoned), instead of standing at it.
TEST_F(LocalizerOnCrossroads, BetweenFixesTheLastFixIsCarriedOnByTheOdometry) {
  const double x = drive_east(5);
  ASSERT_EQ(p.source, PositionSource::gps);  // the fix at t = 5 s, x = -200
  for (int k = 51; k <= 57; ++k) p = loc.on_odometry({0.1 * k, 1.0, 0.0});
  EXPECT_EQ(p.source, PositionSource::gps);
  EXPECT_NEAR(p.match.point.x_m, x + 7.0, 1.5);
}

}  // namespace
}  // namespace corridor::localizer
