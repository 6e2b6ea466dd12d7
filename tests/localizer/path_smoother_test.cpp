// The smoother along a matched path: a fix set aside is placed by its time, and positions are
// averaged along the path with the receiver's speeds.
#include "localizer/match/path_smoother.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <optional>

#include "tests/localizer/sketch_graph.hpp"

namespace corridor::localizer {
namespace {

using testing::Sketch;
using testing::edge_between;

// A straight two-way road, 1 km, driven east at 10 m/s with a fix a second.
struct StraightDrive {
  maps::RoadGraph g = testing::straight_road(1000.0);
  planner::BoundedDistances distances{g.node_count()};
  std::vector<GpsFix> fixes;
  std::vector<MatchedPoint> points;

  StraightDrive() {
    const EdgeId east = g.position(g.tail(EdgeId{0})).x_m < 1.0 ? EdgeId{0} : EdgeId{1};
    for (int i = 0; i < 30; ++i) {
      const double x = 100.0 + 10.0 * i;
      fixes.push_back({static_cast<double>(i), g.projection().to_lat_lon({x, 0}), 1.0, 90.0, 10.0});
      MatchedPoint m;
      m.matched = true;
      m.edge = east;
      m.offset_m = x;
      m.point = {x, 0};
      points.push_back(m);
    }
  }
};

TEST(PathSmoother, PlacesAFixSetAsideByItsTime) {
  StraightDrive d;
  d.points[12] = MatchedPoint{};  // as the matcher leaves a fix it set aside
  const auto out = smooth_along_path(d.g, d.distances, d.fixes, d.points);
  ASSERT_TRUE(out[12].matched);
  EXPECT_NEAR(out[12].offset_m, 220.0, 1.0);
}

// Each fix's position pulls the estimate by its σ against the filter's own: one 40 m off moves the
// smoothed point there by a fraction of it, and its neighbours less.
TEST(PathSmoother, AveragesAlongThePathWithTheSpeeds) {
  StraightDrive d;
  d.points[15].offset_m += 40.0;
  d.points[15].point.x_m += 40.0;
  const auto out = smooth_along_path(d.g, d.distances, d.fixes, d.points);
  EXPECT_GT(out[15].offset_m, 250.5);
  EXPECT_LT(out[15].offset_m, 270.0);
  EXPECT_NEAR(out[5].offset_m, 150.0, 1.0);
  EXPECT_NEAR(out[25].offset_m, 350.0, 1.0);
}

// The same outlier with the fix before it missing its speed: nothing says whether the fixes before
// the outlier agree among themselves, so the outlier is not taken for the near side of a detour.
TEST(PathSmoother, AnOutlierAfterAFixWithoutASpeedSplitsNothing) {
  StraightDrive d;
  d.points[15].offset_m += 40.0;
  d.points[15].point.x_m += 40.0;
  d.fixes[14].speed_mps.reset();
  const auto out = smooth_along_path(d.g, d.distances, d.fixes, d.points);
  EXPECT_NEAR(out[25].offset_m, 350.0, 1.0);
  EXPECT_NEAR(out[5].offset_m, 150.0, 1.0);
}

// A road west to east through node B (300, 0), with a one-way loop of 88 m off B (a small
// roundabout): B → P → Q → B.
struct LoopDrive {
  maps::RoadGraph g = [] {
    Sketch s;
    s.nodes = {{0, 0}, {300, 0}, {700, 0}, {315, 25}, {285, 25}};
    s.roads = {{{0, 1, 2}, false, 1}, {{1, 3, 4, 1}, true, 2}};
    return s.build();
  }();
  planner::BoundedDistances distances{g.node_count()};
  std::vector<GpsFix> fixes;
  std::vector<MatchedPoint> points;

  EdgeId edge(maps::Point2 from, maps::Point2 to) const { return edge_between(g, from, to); }
  const EdgeId ab = edge({0, 0}, {300, 0}), bc = edge({300, 0}, {700, 0});
  const EdgeId bp = edge({300, 0}, {315, 25}), qb = edge({285, 25}, {300, 0});

  // A fix a second at `speed` (none if NaN), its position and its match at `offset` along `e`.
  void add(EdgeId e, double offset, double speed, double hdop = 1.0) {
    const maps::Point2 p = g.point_along(e, offset);
    fixes.push_back({static_cast<double>(fixes.size()), g.projection().to_lat_lon(p), hdop, std::nullopt,
                     std::isnan(speed) ? std::nullopt : std::optional<double>(speed)});
    MatchedPoint m;
    m.matched = true;
    m.edge = e;
    m.offset_m = offset;
    m.point = p;
    points.push_back(m);
  }
};

// Fixes scattered over a small roundabout can make the most likely path run once round it. The
// speeds say the vehicle drove 10 m a second straight through: the loop is taken out, the two fixes
// on it go onto the road, and the points after it are not pulled 88 m back along the path.
TEST(PathSmoother, TakesOutALoopTheSpeedsSayWasNotDriven) {
  LoopDrive d;
  ASSERT_TRUE(d.ab.valid() && d.bc.valid() && d.bp.valid() && d.qb.valid());
  for (int i = 0; i < 20; ++i) d.add(d.ab, 100.0 + 10.0 * i, 10.0);  // x = 100 … 290
  d.add(d.bp, 5.0, 10.0);   // two fixes noise put on the loop, at x = 300 and 310
  d.add(d.qb, 25.0, 10.0);
  for (int i = 2; i < 20; ++i) d.add(d.bc, 10.0 * i, 10.0);           // x = 320 … 490
  const auto out = smooth_along_path(d.g, d.distances, d.fixes, d.points);
  for (std::size_t i = 0; i < out.size(); ++i) {
    ASSERT_TRUE(out[i].matched) << i;
    EXPECT_TRUE(out[i].edge == d.ab || out[i].edge == d.bc) << "fix " << i << " left on the loop";
    const double x = 100.0 + 10.0 * static_cast<double>(i);
    EXPECT_NEAR(out[i].point.x_m, x, 4.0) << i;
  }
}

// Fixes far out on the loop say the vehicle was there, whatever its speeds say: two fixes on the
// loop's far side, 25 m from the road (over 3σ at σ 4 m), keep it.
TEST(PathSmoother, KeepsALoopItsFixesLieOutOn) {
  LoopDrive d;
  const EdgeId far_side = d.edge({315, 25}, {285, 25});
  for (int i = 0; i < 20; ++i) d.add(d.ab, 100.0 + 10.0 * i, 10.0);
  d.add(far_side, 10.0, 10.0);
  d.add(far_side, 20.0, 10.0);
  for (int i = 2; i < 20; ++i) d.add(d.bc, 10.0 * i, 10.0);
  const auto out = smooth_along_path(d.g, d.distances, d.fixes, d.points);
  std::size_t on_loop = 0;
  for (const MatchedPoint& m : out) on_loop += m.edge == d.bp || m.edge == far_side || m.edge == d.qb ? 1 : 0;
  EXPECT_GE(on_loop, 2u);
}

// A vehicle that does drive round the loop (its speeds cover the 88 m) keeps it. Its fixes there
// are poor (HDOP 3: 3σ is 36 m, more than the loop lies from the road), so the speeds alone decide.
TEST(PathSmoother, KeepsALoopTheSpeedsSayWasDriven) {
  LoopDrive d;
  for (int i = 0; i < 20; ++i) d.add(d.ab, 100.0 + 10.0 * i, 10.0);  // x = 100 … 290
  const EdgeId loop[] = {d.bp, d.edge({315, 25}, {285, 25}), d.qb};
  const double round = d.g.length_m(loop[0]) + d.g.length_m(loop[1]) + d.g.length_m(loop[2]);
  for (double along = 0.0; along < round; along += 10.0) {  // round it at 10 m/s
    std::size_t k = 0;
    double offset = along;
    while (k < 2 && offset > d.g.length_m(loop[k])) offset -= d.g.length_m(loop[k++]);
    d.add(loop[k], offset, 10.0, 3.0);
  }
  for (int i = 0; i < 15; ++i) d.add(d.bc, 5.0 + 10.0 * i, 10.0);
  const auto out = smooth_along_path(d.g, d.distances, d.fixes, d.points);
  std::size_t on_loop = 0;
  for (const MatchedPoint& m : out) on_loop += m.edge == loop[0] || m.edge == loop[1] || m.edge == loop[2] ? 1 : 0;
  EXPECT_GE(on_loop, 7u);
}

// Without speeds nothing says how far the vehicle drove: the loop stays as matched, even where its
// fixes lie near the road.
TEST(PathSmoother, KeepsALoopWithoutSpeeds) {
  LoopDrive d;
  const double none = std::nan("");
  for (int i = 0; i < 20; ++i) d.add(d.ab, 100.0 + 10.0 * i, none);
  d.add(d.bp, 5.0, none);
  d.add(d.qb, 25.0, none);
  for (int i = 2; i < 20; ++i) d.add(d.bc, 10.0 * i, none);
  const auto out = smooth_along_path(d.g, d.distances, d.fixes, d.points);
  std::size_t on_loop = 0;
  for (const MatchedPoint& m : out) on_loop += m.edge == d.bp || m.edge == d.qb || m.edge == d.edge({315, 25}, {285, 25}) ? 1 : 0;
  EXPECT_GE(on_loop, 1u);
}

// A minute without fixes (a tunnel) between a fix at 10 m/s and a queue at its far end: the two
// speeds' trapezoid says 310 m were driven where the path says 660. Over a gap that long the
// speeds measure nothing, so this is no detour: the chain is smoothed whole, and the fix set
// aside just before the gap is placed on the road (a split would leave it without an estimate).
TEST(PathSmoother, ASpeedBeforeALongGapSaysNothingOfTheDistanceDriven) {
  StraightDrive d;
  d.fixes.resize(16);
  d.points.resize(16);
  d.points[15] = MatchedPoint{};  // x = 250, set aside
  for (int i = 0; i < 5; ++i) {
    const double x = 900.0;
    d.fixes.push_back({75.0 + i, d.g.projection().to_lat_lon({x, 0}), 1.0, 90.0, 0.0});
    MatchedPoint m = d.points[14];
    m.offset_m = x;
    m.point = {x, 0};
    d.points.push_back(m);
  }
  const auto out = smooth_along_path(d.g, d.distances, d.fixes, d.points);
  ASSERT_TRUE(out[15].matched);
  EXPECT_NEAR(out[15].offset_m, 250.0, 5.0);
  EXPECT_NEAR(out[20].offset_m, 900.0, 3.0);
}

// The road from the west ends at (300, 0) and goes on at (320, 0); our graph joins the two ends
// only by a detour 63 m long through (310, 30) (SUMO's vehicle drove a link our importer left
// out). A fix a second at 10 m/s from x = 100 to 490; the two in the gap (x = 310 and 320) are set
// aside, so four fixes span it in 3 s; the path between them is 73 m, the speeds say 30, and the
// rule on the fixes' spacing alone (2 × 30 + 30 m) lets it through.
struct DetourDrive {
  maps::RoadGraph g = [] {
    Sketch s;
    s.nodes = {{0, 0}, {300, 0}, {310, 30}, {320, 0}, {700, 0}};
    s.roads = {{{0, 1}, true, 1}, {{1, 2, 3}, true, 2}, {{3, 4}, true, 3}};
    return s.build();
  }();
  planner::BoundedDistances distances{g.node_count()};
  EdgeId west = edge_between(g, {0, 0}, {300, 0}), east = edge_between(g, {320, 0}, {700, 0});
  std::vector<GpsFix> fixes;
  std::vector<MatchedPoint> points;

  // `fix_at` says where the fix of the vehicle at x lies.
  explicit DetourDrive(const std::function<maps::Point2(double)>& fix_at) {
    for (int i = 0; i < 40; ++i) {
      const double x = 100.0 + 10.0 * i;
      fixes.push_back({static_cast<double>(i), g.projection().to_lat_lon(fix_at(x)), 1.0, 90.0, 10.0});
      MatchedPoint m;
      if (x <= 300.0 || x >= 330.0) {
        m.matched = true;
        m.edge = x <= 300.0 ? west : east;
        m.offset_m = x <= 300.0 ? x : x - 320.0;
        m.point = {x, 0};
      }
      points.push_back(m);
    }
  }
};

// Split at the detour, neither side is dragged along it.
TEST(PathSmoother, SplitsTheChainAtAMoveTheSpeedsSayWasADetour) {
  DetourDrive d([](double x) { return maps::Point2{x, 0}; });
  const auto out = smooth_along_path(d.g, d.distances, d.fixes, d.points);
  for (std::size_t i = 0; i < out.size(); ++i) {
    if (!d.points[i].matched) continue;
    EXPECT_NEAR(out[i].point.x_m, 100.0 + 10.0 * static_cast<double>(i), 3.0) << i;
    EXPECT_NEAR(out[i].point.y_m, 0.0, 0.5) << i;
  }
}

// The same split, with the gap's fixes: the vehicle was somewhere between the edge the first part
// ends on and the edge the second starts on, so a fix set aside in the gap goes to the nearer of
// the two; one 40 m off the road (10σ) keeps no estimate.
TEST(PathSmoother, AFixInTheGapOfASplitChainGoesToTheNearerEdgeAroundIt) {
  DetourDrive d([](double x) {
    if (x == 310.0) return maps::Point2{303.0, 0.0};
    return maps::Point2{x, x == 320.0 ? 40.0 : 0.0};  // the second fix in the gap is a multipath one
  });
  const auto out = smooth_along_path(d.g, d.distances, d.fixes, d.points);
  ASSERT_TRUE(out[21].matched);  // x = 303, 3 m past the west edge's end, 17 m before the east one
  EXPECT_EQ(out[21].edge, d.west);
  EXPECT_NEAR(out[21].offset_m, 300.0, 0.5);
  EXPECT_FALSE(out[22].matched);
}

// The corner model's figures: 2·8 − 8·π/2 ± 1.75·π/2 through a right angle; less where the pieces
// either side are too short for the arc; a hairpin sharper than 149° what 149° saves; nothing
// straight on, nor for a NaN.
TEST(CornerCut, SavesWhatTheArcAndTheLaneSaveAndNoMoreThroughAHairpin) {
  const double pi = 3.14159265358979;
  EXPECT_NEAR(corner_cut(pi / 2, 50, 50, 8.0, 1.75).saving_m, 16.0 - 4.0 * pi + 0.875 * pi, 1e-9);
  EXPECT_NEAR(corner_cut(-pi / 2, 50, 50, 8.0, 1.75).saving_m, 16.0 - 4.0 * pi - 0.875 * pi, 1e-9);
  EXPECT_NEAR(corner_cut(pi / 2, 4, 50, 8.0, 1.75).saving_m, 4.0 - pi + 0.875 * pi, 1e-9);  // a 2 m arc
  const double t = std::tan(0.5 * kMaxCornerRad);  // the arc's radius is cut to fit 50 m pieces: 25 / t
  EXPECT_NEAR(corner_cut(pi, 50, 50, 8.0, 1.75).saving_m, 50.0 - 25.0 / t * kMaxCornerRad + 1.75 * kMaxCornerRad, 1e-9);
  EXPECT_NEAR(corner_cut(-160.0 * pi / 180.0, 50, 50, 8.0, 1.75).saving_m, 50.0 - 25.0 / t * kMaxCornerRad - 1.75 * kMaxCornerRad, 1e-9);
  EXPECT_EQ(corner_cut(std::nan(""), 50, 50, 8.0, 1.75).saving_m, 0.0);
  EXPECT_EQ(corner_cut(0.0, 50, 50, 8.0, 1.75).saving_m, 0.0);
}

// A two-way road east to B (300, 0), then a 90° turn onto one that runs on south (right where
// traffic keeps right) or north (left). A vehicle at 10 m/s rounds the corner on an 8 m arc 1.75 m
// to its side of the centre lines: through a right turn it drives 2·8 − 8·π/2 + 1.75·π/2 = 6.18 m
// less than the centre lines, through a left one 2·8 − 8·π/2 − 1.75·π/2 = 0.68 m less. Its speeds
// say so; its fixes (HDOP 4, σ 16 m, and so only loosely held) lie on the centre lines. Smoothed
// on the centre lines, the speeds' 6 m disagree with the fixes and pull the track off them round
// the corner; on the distance driven they agree.
maps::RoadGraph corner(double turn_sign, bool left_hand_traffic) {
  Sketch sk;
  sk.nodes = {{0, 0}, {300, 0}, {300, -300 * turn_sign}};
  sk.roads = {{{0, 1, 2}, false, 1}};
  maps::RoadGraphData data = sk.build().data();
  if (left_hand_traffic) data.left_hand_traffic = {1};
  return maps::RoadGraph(std::move(data));
}

struct Corner {
  maps::RoadGraph g;
  std::vector<GpsFix> fixes;
  std::vector<MatchedPoint> points;
  std::vector<double> s;  // the truth, along the centre lines
  EdgeId first, second;

  Corner(double turn_sign, bool left_hand_traffic) : g(corner(turn_sign, left_hand_traffic)) {
    first = edge_between(g, {0, 0}, {300, 0});
    second = edge_between(g, {300, 0}, {300, -300 * turn_sign});
    const bool shorter_side = (turn_sign > 0) != left_hand_traffic;  // turning to the side traffic keeps to
    const double saved = 16.0 - 8.0 * M_PI / 2.0 + (shorter_side ? 1.75 : -1.75) * M_PI / 2.0;
    for (int i = 0; i < 50; ++i) {
      const double driven = 100.0 + 10.0 * i;
      // Along the centre lines: the corner's saving spread over its arc, 8 m either side of B.
      const double along = driven + saved * std::clamp((driven - (300.0 - 8.0)) / (16.0 - saved), 0.0, 1.0);
      s.push_back(along);
      MatchedPoint m;
      m.matched = true;
      m.edge = along <= 300.0 ? first : second;
      m.offset_m = along <= 300.0 ? along : along - 300.0;
      m.point = g.point_along(m.edge, m.offset_m);
      points.push_back(m);
      fixes.push_back({static_cast<double>(i), g.projection().to_lat_lon(m.point), 4.0, std::nullopt, 10.0});
    }
  }
  // The largest distance between a smoothed point and the truth, along the centre lines.
  double worst(const SmootherConfig& config) {
    planner::BoundedDistances distances{g.node_count()};
    const auto out = smooth_along_path(g, distances, fixes, points, config);
    double worst_m = 0.0;
    for (std::size_t i = 0; i < out.size(); ++i) {
      const double along = out[i].edge == first ? out[i].offset_m : 300.0 + out[i].offset_m;
      worst_m = std::max(worst_m, std::abs(along - s[i]));
    }
    return worst_m;
  }
};

TEST(PathSmoother, TheSpeedsMeasureTheDistanceDrivenRoundACorner) {
  SmootherConfig centre_lines;
  centre_lines.corner = {0.0, 0.0};
  Corner right(1.0, false);
  EXPECT_GT(right.worst(centre_lines), 1.5);
  EXPECT_LT(right.worst({}), 0.3);
  // Turning away from the side traffic keeps to, the vehicle drives the outside of the corner.
  Corner left(-1.0, false);
  EXPECT_LT(left.worst({}), 0.3);
  // Where traffic keeps left, a left turn is the short one.
  Corner left_in_left_hand_traffic(-1.0, true);
  EXPECT_LT(left_in_left_hand_traffic.worst({}), 0.3);
  EXPECT_GT(left_in_left_hand_traffic.worst(centre_lines), 1.5);
}

}  // namespace
}  // namespace corridor::localizer
