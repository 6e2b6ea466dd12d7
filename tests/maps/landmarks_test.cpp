// ALT landmarks: admissible and exactly consistent against free-flow Dijkstra, on random grids (all
// pairs) and on the shared OSM extracts (sampled), and tight at the landmarks themselves.
#include "maps/landmarks.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <functional>
#include <queue>
#include <random>

#include "maps/errors.hpp"
#include "maps/graph_cache.hpp"
#include "maps/osm_import.hpp"
#include "maps/synthetic_grid.hpp"

namespace corridor::maps {
namespace {

// Free-flow Dijkstra in ticks from `source`: the oracle, independent of the landmark code's own.
std::vector<std::uint64_t> oracle_ticks(const RoadGraph& g, NodeId source) {
  std::vector<std::uint64_t> dist(g.node_count(), UINT64_MAX);
  using Item = std::pair<std::uint64_t, std::uint32_t>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> open;
  dist[source.index()] = 0;
  open.emplace(0, source.v);
  while (!open.empty()) {
    const auto [d, u] = open.top();
    open.pop();
    if (d != dist[u]) continue;
    for (EdgeId e : g.out_edges(NodeId{u})) {
      const std::uint64_t nd = d + free_flow_ticks(g.length_m(e), g.speed_mps(e));
      if (nd < dist[g.head(e).index()]) {
        dist[g.head(e).index()] = nd;
        open.emplace(nd, g.head(e).v);
      }
    }
  }
  return dist;
}

std::int64_t bound(const RoadGraph& g, NodeId a, NodeId b) {
  return landmark_bound_ticks(g.landmarks_from(a), g.landmarks_to(a), g.landmarks_from(b), g.landmarks_to(b));
}

// For every edge u -> v and target t: h(u, t) <= w(u, v) + h(v, t), and (backward) h(s, v) <= h(s, u) + w.
void expect_consistent(const RoadGraph& g, NodeId t) {
  for (EdgeId e : g.edges()) {
    const std::int64_t w = free_flow_ticks(g.length_m(e), g.speed_mps(e));
    ASSERT_LE(bound(g, g.tail(e), t), w + bound(g, g.head(e), t)) << "edge " << e.v << " target " << t.v;
    ASSERT_LE(bound(g, t, g.head(e)), bound(g, t, g.tail(e)) + w) << "edge " << e.v << " source " << t.v;
  }
}

void expect_admissible_from(const RoadGraph& g, NodeId s) {
  const auto truth = oracle_ticks(g, s);
  for (NodeId v : g.nodes()) {
    if (truth[v.index()] == UINT64_MAX) continue;
    ASSERT_LE(bound(g, s, v), static_cast<std::int64_t>(truth[v.index()])) << s.v << " -> " << v.v;
  }
}

TEST(Landmarks, AdmissibleAndConsistentOnRandomGridsForAllPairs) {
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    GridSpec spec;
    spec.rows = 9;
    spec.cols = 11;
    spec.seed = seed;
    spec.removal_fraction = 0.15;
    spec.oneway_fraction = 0.4;
    spec.diagonal_fraction = 0.1;
    const RoadGraph g = make_perturbed_grid(spec);
    ASSERT_EQ(g.landmark_count(), std::min<std::size_t>(kDefaultLandmarkCount, g.node_count()));
    for (NodeId s : g.nodes()) {
      expect_admissible_from(g, s);
      expect_consistent(g, s);
      EXPECT_EQ(bound(g, s, s), 0);
    }
  }
}

TEST(Landmarks, ExactFromAndToEachLandmark) {
  GridSpec spec;
  spec.rows = 12;
  spec.cols = 12;
  spec.seed = 7;
  const RoadGraph g = make_perturbed_grid(spec);
  const auto& nodes = g.data().landmarks.nodes;
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    const auto from = oracle_ticks(g, nodes[i]);
    for (NodeId v : g.nodes()) {
      EXPECT_EQ(g.landmarks_from(v)[i], from[v.index()]);
      EXPECT_EQ(bound(g, nodes[i], v), static_cast<std::int64_t>(from[v.index()]));  // tight at landmarks
    }
  }
}

TEST(Landmarks, StartAtOppositeCornersAndAreDistinct) {
  GridSpec spec;
  spec.rows = 20;
  spec.cols = 20;
  spec.removal_fraction = 0.0;
  spec.oneway_fraction = 0.0;
  spec.diagonal_fraction = 0.0;
  spec.jitter_fraction = 0.0;
  spec.min_speed_kmh = spec.max_speed_kmh = 50.0;  // time is distance: "farthest" is geometric
  const RoadGraph g = make_perturbed_grid(spec);
  auto nodes = g.data().landmarks.nodes;
  std::sort(nodes.begin(), nodes.end());
  EXPECT_EQ(std::unique(nodes.begin(), nodes.end()), nodes.end());
  // Farthest selection starts at opposite corners of the grid.
  const auto& chosen = g.data().landmarks.nodes;
  EXPECT_GE(distance_m(g.position(chosen[0]), g.position(chosen[1])),
            0.99 * distance_m(g.min_corner(), g.max_corner()));
}

TEST(Landmarks, SurviveTheGraphCache) {
  const RoadGraph g = make_perturbed_grid(GridSpec{});
  const auto file = std::filesystem::temp_directory_path() / "corridor_landmarks_cache_test.cgr";
  write_graph_cache(file, g, {});
  const RoadGraph back = read_graph_cache(file);
  std::filesystem::remove(file);
  EXPECT_EQ(back.data().landmarks.nodes, g.data().landmarks.nodes);
  EXPECT_EQ(back.data().landmarks.from_ticks, g.data().landmarks.from_ticks);
  EXPECT_EQ(back.data().landmarks.to_ticks, g.data().landmarks.to_ticks);
}

TEST(Landmarks, RejectsTablesOfTheWrongSize) {
  RoadGraphData d = make_perturbed_grid(GridSpec{}).data();
  d.landmarks.to_ticks.pop_back();
  EXPECT_THROW(RoadGraph{d}, MapError);
}

class SharedExtractLandmarks : public ::testing::TestWithParam<const char*> {};

TEST_P(SharedExtractLandmarks, AdmissibleAndConsistentOnRealRoads) {
  const auto file = std::filesystem::path(CORRIDOR_SHARED_DATA_DIR) / "osm" / GetParam();
  if (!std::filesystem::exists(file)) GTEST_SKIP() << "shared data not present: " << file;
  const RoadGraph g = import_osm(file, {});
  ASSERT_EQ(g.landmark_count(), kDefaultLandmarkCount);
  std::mt19937_64 rng(11);
  std::uniform_int_distribution<std::uint32_t> any(0, static_cast<std::uint32_t>(g.node_count() - 1));
  for (int i = 0; i < 8; ++i) {
    const NodeId s{any(rng)};
    expect_admissible_from(g, s);
    expect_consistent(g, s);
  }
}

INSTANTIATE_TEST_SUITE_P(Extracts, SharedExtractLandmarks,
                         ::testing::Values("monaco.osm.gz", "liechtenstein.osm.pbf"));

}  // namespace
}  // namespace corridor::maps
