// The vehicle tracker's rules: what moves a vehicle and what is only stored.
#include "server/vehicle_tracker.hpp"

#include <gtest/gtest.h>

#include "tests/server/api_fixture.hpp"

namespace corridor::server {
namespace {

const maps::RoadGraph& grid() { return testing::api_grid(); }

PositionReport report(const std::string& vehicle, EdgeId e, double offset_m, double t) {
  PositionReport p;
  p.vehicle_id = vehicle;
  p.position = grid().projection().to_lat_lon(grid().point_along(e, offset_m));
  p.timestamp_s = t;
  return p;
}

TEST(VehicleTracker, FollowsInOrderReportsOntoTheirRoad) {
  const maps::EdgeSnapper snapper(grid());
  VehicleTracker tracker(grid(), snapper);
  const EdgeId e{5};
  for (int i = 0; i < 5; ++i) {
    const TrackResult r = tracker.track(report("a", e, 20.0 + 10.0 * i, i));
    EXPECT_EQ(r.disposition, Disposition::followed);
    ASSERT_TRUE(r.match.matched);
    EXPECT_TRUE(r.match.edge == e || r.match.edge == grid().twin(e));
  }
  // Driving forward along e: the matcher settles on e's direction, not its twin's.
  EXPECT_EQ(tracker.track(report("a", e, 80.0, 6)).match.edge, e);
}

TEST(VehicleTracker, StaleAndDuplicateReportsAreNotFollowed) {
  const maps::EdgeSnapper snapper(grid());
  VehicleTracker tracker(grid(), snapper);
  const EdgeId e{5};
  ASSERT_EQ(tracker.track(report("a", e, 20.0, 10.0)).disposition, Disposition::followed);
  EXPECT_EQ(tracker.track(report("a", e, 30.0, 9.0)).disposition, Disposition::stale);
  EXPECT_EQ(tracker.track(report("a", e, 20.0, 10.0)).disposition, Disposition::duplicate);
  EXPECT_EQ(tracker.track(report("a", e, 40.0, 10.0)).disposition, Disposition::stale);  // same time, elsewhere
  EXPECT_EQ(tracker.track(report("a", e, 30.0, 11.0)).disposition, Disposition::followed);
  // Each vehicle keeps its own clock.
  EXPECT_EQ(tracker.track(report("b", e, 30.0, 1.0)).disposition, Disposition::followed);
}

TEST(VehicleTracker, AnImpossibleJumpIsAnOutlierUntilItPersists) {
  const maps::EdgeSnapper snapper(grid());
  VehicleTracker tracker(grid(), snapper);
  const EdgeId near{0};
  const EdgeId far{static_cast<std::uint32_t>(grid().edge_count() - 1)};
  ASSERT_GT(maps::distance_m(grid().position(grid().tail(near)), grid().position(grid().tail(far))), 500.0);
  ASSERT_EQ(tracker.track(report("a", near, 10.0, 0.0)).disposition, Disposition::followed);
  // 1 s later, hundreds of metres away: faster than any vehicle.
  EXPECT_EQ(tracker.track(report("a", far, 10.0, 1.0)).disposition, Disposition::outlier);
  EXPECT_EQ(tracker.track(report("a", near, 15.0, 2.0)).disposition, Disposition::followed);  // back on track
  // Three in a row: the vehicle really is there (a long tunnel, a tow): follow it, a new chain.
  EXPECT_EQ(tracker.track(report("a", far, 10.0, 3.0)).disposition, Disposition::outlier);
  EXPECT_EQ(tracker.track(report("a", far, 12.0, 4.0)).disposition, Disposition::outlier);
  const TrackResult moved = tracker.track(report("a", far, 14.0, 5.0));
  EXPECT_EQ(moved.disposition, Disposition::followed);
  EXPECT_TRUE(moved.match.chain_start);
}

TEST(VehicleTracker, PoorGpsIsNotFollowedButOdometryIs) {
  const maps::EdgeSnapper snapper(grid());
  VehicleTracker tracker(grid(), snapper);
  PositionReport poor = report("a", EdgeId{5}, 20.0, 1.0);
  poor.hdop = 12.0;
  EXPECT_EQ(tracker.track(poor).disposition, Disposition::low_accuracy);
  poor.source = "vo";  // the vehicle's own odometry reports without a usable HDOP limit
  EXPECT_EQ(tracker.track(poor).disposition, Disposition::followed);
  PositionReport good = report("a", EdgeId{5}, 30.0, 2.0);
  good.hdop = 1.0;
  EXPECT_EQ(tracker.track(good).disposition, Disposition::followed);
}

}  // namespace
}  // namespace corridor::server
