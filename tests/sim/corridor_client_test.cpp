// The closed loop and `corridor localize` name a vehicle in a URL path: an id the server would
// otherwise read as another vehicle, or as another path, is percent-encoded.
#include "sim/corridor_client.hpp"

#include <gtest/gtest.h>

namespace corridor::sim {
namespace {

TEST(CorridorClient, PathSegmentsEncodeAllButUnreservedBytes) {
  EXPECT_EQ(path_segment("ev-grid_1.run~2"), "ev-grid_1.run~2");
  EXPECT_EQ(path_segment("unit 7"), "unit%207");
  EXPECT_EQ(path_segment("a/b%c?d#e"), "a%2Fb%25c%3Fd%23e");
  EXPECT_EQ(path_segment("\xC3\xA9"), "%C3%A9");  // é in UTF-8
  EXPECT_EQ(path_segment(""), "");
}

}  // namespace
}  // namespace corridor::sim
