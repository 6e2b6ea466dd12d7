#include "maps/geo.hpp"

#include <gtest/gtest.h>

namespace corridor::maps {
namespace {

TEST(LocalProjection, RoundTripsAndIsMetric) {
  const LocalProjection proj({43.7384, 7.4246});
  const Point2 origin = proj.to_local({43.7384, 7.4246});
  EXPECT_NEAR(origin.x_m, 0.0, 1e-6);
  EXPECT_NEAR(origin.y_m, 0.0, 1e-6);
  // One arc-minute of latitude is about 1852 m (1849 m at this latitude on WGS84).
  const Point2 north = proj.to_local({43.7384 + 1.0 / 60.0, 7.4246});
  EXPECT_NEAR(north.y_m, 1852.0, 5.0);
  EXPECT_NEAR(north.x_m, 0.0, 0.1);
  // The frame is a tangent plane and heights are dropped, so a round trip 1.4 km out is exact to
  // tens of micrometres, not to rounding error.
  const LatLon back = proj.to_lat_lon({1234.5, -678.9});
  const Point2 again = proj.to_local(back);
  EXPECT_NEAR(again.x_m, 1234.5, 1e-3);
  EXPECT_NEAR(again.y_m, -678.9, 1e-3);
}

TEST(LatLonValidation, RejectsNonFiniteAndOutOfRange) {
  EXPECT_TRUE(is_valid_lat_lon({43.7, 7.4}));
  EXPECT_TRUE(is_valid_lat_lon({-90, 180}));
  EXPECT_FALSE(is_valid_lat_lon({90.0001, 0}));
  EXPECT_FALSE(is_valid_lat_lon({0, -180.5}));
  EXPECT_FALSE(is_valid_lat_lon({std::nan(""), 0}));
}

}  // namespace
}  // namespace corridor::maps
