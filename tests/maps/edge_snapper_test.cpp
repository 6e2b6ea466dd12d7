#include "maps/edge_snapper.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <random>
#include <vector>

#include "maps/errors.hpp"
#include "maps/synthetic_grid.hpp"

namespace corridor::maps {
namespace {

RoadGraph grid() {
  GridSpec spec;
  spec.rows = 12;
  spec.cols = 12;
  spec.seed = 11;
  return make_perturbed_grid(spec);
}

// Brute force over every polyline segment: the oracle for the R-tree.
double brute_force_distance(const RoadGraph& g, Point2 p) {
  double best = std::numeric_limits<double>::infinity();
  for (EdgeId e : g.edges()) {
    const auto pts = g.geometry(e);
    for (std::size_t i = 1; i < pts.size(); ++i) {
      const double dx = pts[i].x_m - pts[i - 1].x_m, dy = pts[i].y_m - pts[i - 1].y_m;
      const double len2 = dx * dx + dy * dy;
      const double t = len2 > 0 ? std::clamp(((p.x_m - pts[i - 1].x_m) * dx + (p.y_m - pts[i - 1].y_m) * dy) / len2, 0.0, 1.0) : 0.0;
      best = std::min(best, distance_m(p, {pts[i - 1].x_m + t * dx, pts[i - 1].y_m + t * dy}));
    }
  }
  return best;
}

// Points spread uniformly over the map's bounding box, the same ones for the same seed.
std::vector<Point2> random_points(const RoadGraph& g, std::uint64_t seed, int count) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> x(g.min_corner().x_m, g.max_corner().x_m);
  std::uniform_real_distribution<double> y(g.min_corner().y_m, g.max_corner().y_m);
  std::vector<Point2> out;
  for (int i = 0; i < count; ++i) out.push_back({x(rng), y(rng)});
  return out;
}

TEST(EdgeSnapper, NearestPointMatchesBruteForce) {
  const RoadGraph g = grid();
  const EdgeSnapper snapper(g);
  for (const Point2 p : random_points(g, 5, 500)) {
    const SnapResult r = snapper.snap_local(p, {1e6});
    EXPECT_NEAR(r.distance_m, brute_force_distance(g, p), 1e-6);
    // The reported offset lands on the reported point.
    EXPECT_NEAR(distance_m(g.point_along(r.edge, r.offset_m), r.point), 0.0, 1e-6);
    if (r.twin.valid()) {
      EXPECT_NEAR(distance_m(g.point_along(r.twin, r.twin_offset_m), r.point), 0.0, 1e-6);
    }
  }
}

// One edge's nearest point agrees with the snapper's wherever the snapper picks that edge: same
// distance, and an offset that lands on the point.
TEST(RoadGraph, NearestPointOfAnEdgeAgreesWithTheSnapper) {
  const RoadGraph g = grid();
  const EdgeSnapper snapper(g);
  for (const Point2 p : random_points(g, 9, 300)) {
    const SnapResult r = snapper.snap_local(p, {1e6});
    const RoadGraph::EdgePoint q = g.nearest_point(r.edge, p);
    EXPECT_NEAR(q.distance_m, r.distance_m, 1e-6);
    EXPECT_NEAR(q.offset_m, r.offset_m, 1e-6);
    EXPECT_NEAR(distance_m(g.point_along(r.edge, q.offset_m), q.point), 0.0, 1e-6);
  }
}

// Offsets are in the edge's stated length: an edge stated twice as long as it is drawn puts a
// point a third of the way along its drawing at two thirds of its drawn length.
TEST(RoadGraph, NearestPointOffsetIsInTheStatedLength) {
  RoadGraphData d = grid().data();
  const EdgeId e{7};
  const double drawn = d.edge_length_m[e.index()];
  d.edge_length_m[e.index()] = 2.0 * drawn;
  const RoadGraph g(std::move(d));
  const Point2 third = g.point_along(e, g.length_m(e) / 3);  // a third of the way along the drawing
  const RoadGraph::EdgePoint q = g.nearest_point(e, third);
  EXPECT_NEAR(q.distance_m, 0.0, 1e-6);
  EXPECT_NEAR(q.offset_m, 2.0 * drawn / 3, 1e-6);
}

// The two directions of a road may differ in length (a SUMO net's lanes do): the twin's offset is
// the same share of the way from the other end, both ends included.
TEST(RoadGraph, TwinOffsetIsTheSameShareFromTheOtherEnd) {
  RoadGraphData d = grid().data();
  EdgeId e;
  for (std::uint32_t i = 0; i < d.edge_twin.size() && !e.valid(); ++i) {
    if (d.edge_twin[i].valid()) e = EdgeId{i};
  }
  ASSERT_TRUE(e.valid());
  const EdgeId t = d.edge_twin[e.index()];
  d.edge_length_m[t.index()] = 1.5 * d.edge_length_m[e.index()];
  const RoadGraph g(std::move(d));
  const double len = g.length_m(e);
  EXPECT_DOUBLE_EQ(g.twin_offset_m(e, 0.0), 1.5 * len);
  EXPECT_DOUBLE_EQ(g.twin_offset_m(e, len), 0.0);
  EXPECT_NEAR(g.twin_offset_m(e, len / 4), 1.5 * len * 0.75, 1e-9);
  EXPECT_NEAR(g.twin_offset_m(t, g.twin_offset_m(e, len / 3)), len / 3, 1e-9);
  EXPECT_DOUBLE_EQ(g.twin_offset_m(e, 2 * len), 0.0);  // clamped onto the twin
}

TEST(EdgeSnapper, LatLonOnARoadSnapsOntoIt) {
  const RoadGraph g = grid();
  const EdgeSnapper snapper(g);
  const EdgeId e{7};
  const Point2 mid = g.point_along(e, g.length_m(e) / 3);
  const SnapResult r = snapper.snap(g.projection().to_lat_lon(mid));
  EXPECT_LT(r.distance_m, 1e-3);
  EXPECT_TRUE(r.edge == e || r.edge == g.twin(e));
  const double expected = r.edge == e ? g.length_m(e) / 3 : g.length_m(e) * 2 / 3;
  EXPECT_NEAR(r.offset_m, expected, 1e-3);
}

TEST(EdgeSnapper, FarFromAnyRoadIsAnError) {
  const RoadGraph g = grid();
  const EdgeSnapper snapper(g);
  // Find a point inside the map that is more than 60 m from every road, then allow only 50 m.
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> x(g.min_corner().x_m, g.max_corner().x_m);
  std::uniform_real_distribution<double> y(g.min_corner().y_m, g.max_corner().y_m);
  Point2 p;
  do {
    p = {x(rng), y(rng)};
  } while (brute_force_distance(g, p) < 60.0);
  try {
    (void)snapper.snap_local(p, {50.0});
    FAIL() << "expected SnapError";
  } catch (const SnapError& e) {
    EXPECT_EQ(e.reason(), SnapError::Reason::too_far_from_road) << e.what();
    EXPECT_NE(std::string(e.what()).find("within 50.0 m"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW((void)snapper.snap_local(p, {SnapOptions{}.max_distance_m}));
}

TEST(EdgeSnapper, OutsideTheMapIsAnError) {
  const RoadGraph g = grid();
  const EdgeSnapper snapper(g);
  try {
    (void)snapper.snap({0.0, 0.0});
    FAIL();
  } catch (const SnapError& e) {
    EXPECT_EQ(e.reason(), SnapError::Reason::outside_map);
    EXPECT_NE(std::string(e.what()).find("outside the map"), std::string::npos);
  }
}

TEST(EdgeSnapper, InvalidCoordinatesAreErrors) {
  const RoadGraph g = grid();
  const EdgeSnapper snapper(g);
  for (LatLon p : {LatLon{91, 9}, LatLon{47, 181}, LatLon{std::nan(""), 9},
                   LatLon{47, std::numeric_limits<double>::infinity()}}) {
    try {
      (void)snapper.snap(p);
      FAIL();
    } catch (const SnapError& e) {
      EXPECT_EQ(e.reason(), SnapError::Reason::invalid_coordinate);
    }
  }
}

}  // namespace
}  // namespace corridor::maps
