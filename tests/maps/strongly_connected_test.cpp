#include "maps/strongly_connected.hpp"

#include <gtest/gtest.h>

namespace corridor::maps {
namespace {

TEST(StronglyConnected, FindsComponentsAndTheLargest) {
  // 0->1->2->0 is a cycle; 2->3, 3->4->3 is a second cycle; 5 is alone.
  const std::vector<std::uint32_t> first_out{0, 1, 2, 4, 5, 6, 6};
  const std::vector<std::uint32_t> head{1, 2, 0, 3, 4, 3};
  const Components c = strongly_connected_components(first_out, head);
  EXPECT_EQ(c.count, 3u);
  EXPECT_EQ(c.component_of[0], c.component_of[1]);
  EXPECT_EQ(c.component_of[1], c.component_of[2]);
  EXPECT_EQ(c.component_of[3], c.component_of[4]);
  EXPECT_NE(c.component_of[0], c.component_of[3]);
  EXPECT_NE(c.component_of[5], c.component_of[3]);
  EXPECT_EQ(c.largest, c.component_of[0]);
}

TEST(StronglyConnected, DeepChainDoesNotOverflowTheStack) {
  // A 200,000-node cycle: recursion would overflow, the iterative version must not.
  const std::uint32_t n = 200000;
  std::vector<std::uint32_t> first_out(n + 1), head(n);
  for (std::uint32_t i = 0; i < n; ++i) {
    first_out[i + 1] = i + 1;
    head[i] = (i + 1) % n;
  }
  const Components c = strongly_connected_components(first_out, head);
  EXPECT_EQ(c.count, 1u);
}

}  // namespace
}  // namespace corridor::maps
