#include "planner/rising_id_queue.hpp"

#include <gtest/gtest.h>

#include <random>
#include <set>

namespace corridor::planner {
namespace {

// Sweeps as the partial customization makes them: a random first batch anywhere, then each taken
// id adds ids above it (some twice, some in the same 64-id word, some thousands of words on). The
// ids come out as an ordered set gives them, each once.
TEST(RisingIdQueue, MatchesAnOrderedSetOverRisingSweeps) {
  constexpr std::uint32_t kIds = 300'000;  // more than one summary word
  RisingIdQueue queue(kIds);
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    std::mt19937_64 rng(seed);
    std::set<std::uint32_t> oracle;
    std::uniform_int_distribution<std::uint32_t> any(0, kIds - 1);
    for (int k = 0; k < 20; ++k) {
      const std::uint32_t id = any(rng);
      queue.push(id);
      queue.push(id);
      oracle.insert(id);
    }
    std::size_t taken = 0;
    while (!queue.empty()) {
      ASSERT_FALSE(oracle.empty());
      const std::uint32_t id = queue.pop();
      ASSERT_EQ(id, *oracle.begin()) << "seed " << seed;
      oracle.erase(oracle.begin());
      ++taken;
      if (taken > 2000) continue;  // let the sweep end
      const int adds = std::uniform_int_distribution<int>(0, 3)(rng);
      for (int a = 0; a < adds; ++a) {
        const std::uint32_t step = std::uniform_int_distribution<int>(0, 3)(rng) == 0
                                       ? std::uniform_int_distribution<std::uint32_t>(1, 50'000)(rng)
                                       : std::uniform_int_distribution<std::uint32_t>(1, 70)(rng);
        if (id + step >= kIds) continue;
        queue.push(id + step);
        oracle.insert(id + step);
      }
    }
    EXPECT_TRUE(oracle.empty()) << "seed " << seed;
    EXPECT_GT(taken, 20u);
  }
}

TEST(RisingIdQueue, TakesTheLastIdAndTheFirst) {
  RisingIdQueue queue(130);
  queue.push(129);
  queue.push(0);
  queue.push(64);
  EXPECT_EQ(queue.pop(), 0u);
  EXPECT_EQ(queue.pop(), 64u);
  queue.push(65);
  EXPECT_EQ(queue.pop(), 65u);
  EXPECT_EQ(queue.pop(), 129u);
  EXPECT_TRUE(queue.empty());
  queue.push(3);  // a new sweep may start below the last one
  EXPECT_EQ(queue.pop(), 3u);
}

}  // namespace
}  // namespace corridor::planner
