// The smoother along a matched path: a fix set aside is placed by its time, and positions are
// averaged along the path with the receiver's speeds.
#include "localizer/match/path_smoother.hpp"

#include <gtest/gtest.h>

#include "tests/localizer/sketch_graph.hpp"

namespace corridor::localizer {
namespace {

using testing::Sketch;

// A straight two-way road, 1 km, driven east at 10 m/s with a fix a second.
struct StraightDrive {
  maps::RoadGraph g = [] {
    Sketch s;
    s.nodes = {{0, 0}, {1000, 0}};
    s.roads = {{{0, 1}, false, 1}};
    return s.build();
  }();
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

}  // namespace
}  // namespace corridor::localizer
