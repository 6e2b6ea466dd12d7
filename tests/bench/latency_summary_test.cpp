#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <random>
#include <vector>

#include "bench/replan_bench.hpp"

namespace corridor::bench {
namespace {

TEST(LatencySummary, NearestRankPercentilesOfShuffledSamples) {
  std::vector<double> ms(200);
  std::iota(ms.begin(), ms.end(), 1.0);  // 1 .. 200
  std::shuffle(ms.begin(), ms.end(), std::mt19937(7));
  const LatencySummary s = summarize_ms(ms);
  EXPECT_EQ(s.count, 200u);
  // Nearest rank: the ceil(q * n)-th smallest sample.
  EXPECT_EQ(s.p50_ms, 100.0);
  EXPECT_EQ(s.p95_ms, 190.0);
  EXPECT_EQ(s.p99_ms, 198.0);
  EXPECT_EQ(s.max_ms, 200.0);
  EXPECT_DOUBLE_EQ(s.mean_ms, 100.5);
}

TEST(LatencySummary, OneSampleIsEveryPercentile) {
  const LatencySummary s = summarize_ms({3.5});
  EXPECT_EQ(s.count, 1u);
  EXPECT_EQ(s.p50_ms, 3.5);
  EXPECT_EQ(s.p99_ms, 3.5);
  EXPECT_EQ(s.max_ms, 3.5);
}

TEST(LatencySummary, NoSamplesGiveZeros) {
  const LatencySummary s = summarize_ms({});
  EXPECT_EQ(s.count, 0u);
  EXPECT_EQ(s.p99_ms, 0.0);
  EXPECT_EQ(s.max_ms, 0.0);
}

TEST(LatencySummary, JsonCarriesEveryFigureUnderItsKey) {
  const nlohmann::json j = to_json(summarize_ms({1.0, 2.0, 3.0, 10.0}));
  EXPECT_EQ(j.at("count"), 4);
  EXPECT_EQ(j.at("p50_ms"), 2.0);
  EXPECT_EQ(j.at("p95_ms"), 10.0);
  EXPECT_EQ(j.at("p99_ms"), 10.0);
  EXPECT_EQ(j.at("max_ms"), 10.0);
  EXPECT_DOUBLE_EQ(j.at("mean_ms").get<double>(), 4.0);
}

}  // namespace
}  // namespace corridor::bench
