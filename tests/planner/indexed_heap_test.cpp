#include "planner/indexed_heap.hpp"

#include <gtest/gtest.h>

#include <random>
#include <set>

namespace corridor::planner {
namespace {

// Random inserts, key increases and decreases, removals and pops against an ordered set: the top
// is always the smallest (key, id) present, and membership always agrees.
TEST(IndexedHeap, MatchesAnOrderedSetUnderRandomOperations) {
  constexpr std::uint32_t kIds = 200;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    std::mt19937_64 rng(seed);
    IndexedHeap<int> heap(kIds);
    std::set<std::pair<int, std::uint32_t>> oracle;
    std::vector<int> key_of(kIds, 0);
    std::uniform_int_distribution<std::uint32_t> any_id(0, kIds - 1);
    std::uniform_int_distribution<int> any_key(0, 50);  // many ties
    std::uniform_int_distribution<int> op(0, 9);
    for (int step = 0; step < 5000; ++step) {
      const std::uint32_t id = any_id(rng);
      const int o = op(rng);
      if (o < 6) {
        if (heap.contains(id)) oracle.erase({key_of[id], id});
        key_of[id] = any_key(rng);
        heap.push_or_update(id, key_of[id]);
        oracle.insert({key_of[id], id});
      } else if (o < 8) {
        if (heap.contains(id)) oracle.erase({key_of[id], id});
        heap.remove(id);
      } else if (!heap.empty()) {
        const std::uint32_t top = heap.top();
        ASSERT_EQ(oracle.erase({key_of[top], top}), 1u);
        heap.remove(top);
      }
      ASSERT_EQ(heap.size(), oracle.size()) << "seed " << seed << " step " << step;
      ASSERT_EQ(heap.contains(id), oracle.count({key_of[id], id}) == 1) << "seed " << seed << " step " << step;
      if (!heap.empty()) {
        // Ties may surface in any order; the key must be the smallest.
        ASSERT_EQ(heap.top_key(), oracle.begin()->first) << "seed " << seed << " step " << step;
        ASSERT_EQ(key_of[heap.top()], heap.top_key());
      }
    }
    heap.clear();
    EXPECT_TRUE(heap.empty());
    for (std::uint32_t i = 0; i < kIds; ++i) EXPECT_FALSE(heap.contains(i));
  }
}

}  // namespace
}  // namespace corridor::planner
