#include "maps/graph_cache.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <thread>

#include "maps/errors.hpp"
#include "maps/map_loader.hpp"
#include "maps/synthetic_grid.hpp"
#include "tests/maps/osm_fixture.hpp"

namespace corridor::maps {
namespace {

using testing::TempDir;

RoadGraph small_grid() {
  GridSpec spec;
  spec.rows = 6;
  spec.cols = 7;
  spec.seed = 3;
  return make_perturbed_grid(spec);
}

void expect_same_graph(const RoadGraph& a, const RoadGraph& b) {
  ASSERT_EQ(a.node_count(), b.node_count());
  ASSERT_EQ(a.edge_count(), b.edge_count());
  EXPECT_EQ(a.data().first_out, b.data().first_out);
  EXPECT_EQ(a.data().edge_head, b.data().edge_head);
  EXPECT_EQ(a.data().edge_length_m, b.data().edge_length_m);
  EXPECT_EQ(a.data().edge_twin, b.data().edge_twin);
  EXPECT_EQ(a.data().node_signalized, b.data().node_signalized);
  EXPECT_EQ(a.data().in_edge, b.data().in_edge);
  EXPECT_EQ(a.data().geometry.size(), b.data().geometry.size());
  EXPECT_DOUBLE_EQ(a.projection().origin().lat_deg, b.projection().origin().lat_deg);
}

TEST(GraphCache, RoundTripPreservesTheGraph) {
  TempDir dir;
  const RoadGraph g = small_grid();
  const auto file = dir.path() / "g.cgr";
  write_graph_cache(file, g, CacheSource{123, 456});
  EXPECT_TRUE(looks_like_graph_cache(file));
  CacheSource source;
  const RoadGraph back = read_graph_cache(file, &source);
  expect_same_graph(g, back);
  EXPECT_EQ(source, (CacheSource{123, 456}));
}

// Turn restrictions, limits, roundabouts and gates survive the cache; the turn graph rebuilt from them on
// load is the same.
TEST(GraphCache, RoundTripKeepsTheTurnModel) {
  TempDir dir;
  RoadGraphData d = small_grid().data();
  const EdgeId a{0};
  const EdgeId b = *RoadGraph(d).out_edges(d.edge_head[0]).begin();
  d.restrictions.add({a, b}, false, RestrictionMode::motorcar, true);
  d.edge_limits.push_back({a, 3.2f, 0.0f, 7.5f});
  d.roundabout_edges.push_back(b);
  d.left_hand_traffic = {1};
  d.node_stop.assign(d.node_x_m.size(), 0);
  d.node_stop[3] = 1;
  const RoadGraph g(std::move(d));
  const auto file = dir.path() / "t.cgr";
  write_graph_cache(file, g, CacheSource{1, 2});
  const RoadGraph back = read_graph_cache(file);
  EXPECT_EQ(back.data().restrictions.edges, g.data().restrictions.edges);
  EXPECT_EQ(back.data().restrictions.mode, g.data().restrictions.mode);
  EXPECT_EQ(back.data().restrictions.except, g.data().restrictions.except);
  ASSERT_EQ(back.edge_limits().size(), 1u);
  EXPECT_FLOAT_EQ(back.edge_limits()[0].max_height_m, 3.2f);
  EXPECT_TRUE(back.on_roundabout(b));
  EXPECT_TRUE(back.left_hand_traffic());
  EXPECT_EQ(back.data().node_stop, g.data().node_stop);
  EXPECT_TRUE(back.stop_at(NodeId{3}));
  EXPECT_EQ(back.turns().arc_count(), g.turns().arc_count());
}

// A crafted restriction table (offsets that wrap, edges out of range, edges that do not meet) is
// refused with a MapError, never read out of bounds.
TEST(GraphCache, InconsistentRestrictionsAreRejected) {
  const RoadGraph g = small_grid();
  auto with = [&](std::vector<std::uint32_t> first, std::vector<EdgeId> edges) {
    RoadGraphData d = g.data();
    const std::size_t n = first.size() - 1;
    d.restrictions.first = std::move(first);
    d.restrictions.edges = std::move(edges);
    d.restrictions.only.assign(n, 0);
    d.restrictions.mode.assign(n, 0);
    d.restrictions.except.assign(n, 0);
    return d;
  };
  const EdgeId e0{0};
  EXPECT_THROW(RoadGraph(with({0, 0xFFFFFFFFu, 5}, {e0, e0, e0, e0, e0})), MapError);
  EXPECT_THROW(RoadGraph(with({0, 2}, {e0, EdgeId{999999}})), MapError);
  const EdgeId far{static_cast<std::uint32_t>(g.edge_count() - 1)};
  ASSERT_NE(g.tail(far), g.head(e0));
  EXPECT_THROW(RoadGraph(with({0, 2}, {e0, far})), MapError);
  RoadGraphData bad_limits = g.data();
  bad_limits.edge_limits.push_back({EdgeId{0}, std::nanf(""), 0, 0});
  EXPECT_THROW(RoadGraph(std::move(bad_limits)), MapError);
}

TEST(GraphCache, CorruptByteIsDetected) {
  TempDir dir;
  const auto file = dir.path() / "g.cgr";
  write_graph_cache(file, small_grid(), {});
  {
    std::fstream f(file, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(200);
    f.put('\x5a');
  }
  EXPECT_THROW((void)read_graph_cache(file), GraphCacheError);
}

TEST(GraphCache, TruncatedFileIsDetected) {
  TempDir dir;
  const auto file = dir.path() / "g.cgr";
  write_graph_cache(file, small_grid(), {});
  std::filesystem::resize_file(file, std::filesystem::file_size(file) / 2);
  EXPECT_THROW((void)read_graph_cache(file), GraphCacheError);
}

TEST(GraphCache, OtherVersionIsRejectedWithAHint) {
  TempDir dir;
  const auto file = dir.path() / "g.cgr";
  write_graph_cache(file, small_grid(), {});
  {
    std::fstream f(file, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(8);
    const std::uint32_t version = kGraphCacheVersion + 1;
    f.write(reinterpret_cast<const char*>(&version), sizeof version);
  }
  try {
    (void)read_graph_cache(file);
    FAIL();
  } catch (const GraphCacheError& e) {
    EXPECT_NE(std::string(e.what()).find("re-import"), std::string::npos) << e.what();
  }
}

TEST(GraphCache, NotACacheIsRejected) {
  TempDir dir;
  const auto file = dir.path() / "x.cgr";
  std::ofstream(file) << "<?xml version='1.0'?><osm></osm>";
  EXPECT_FALSE(looks_like_graph_cache(file));
  EXPECT_THROW((void)read_graph_cache(file), GraphCacheError);
}

TEST(MapLoader, ImportsOnceThenReusesTheCacheUntilTheSourceChanges) {
  TempDir dir;
  const auto osm = dir.path() / "town.osm";
  testing::write_osm(osm, {{1, 47.0, 9.5, {}}, {2, 47.001, 9.5, {}}},
                     {{1, {1, 2}, {{"highway", "residential"}}}});
  MapLoadOptions options;
  options.cache_dir = dir.path() / "cache";
  options.import.show_progress = false;
  MapLoadInfo info;
  const RoadGraph first = load_map(osm, options, &info);
  EXPECT_EQ(info.origin, MapLoadInfo::Origin::imported);
  ASSERT_TRUE(std::filesystem::exists(info.cache_file));
  const RoadGraph second = load_map(osm, options, &info);
  EXPECT_EQ(info.origin, MapLoadInfo::Origin::cache);
  expect_same_graph(first, second);

  // A changed source invalidates the cache.
  testing::write_osm(osm, {{1, 47.0, 9.5, {}}, {2, 47.001, 9.5, {}}, {3, 47.001, 9.501, {}}},
                     {{1, {1, 2}, {{"highway", "residential"}}}, {2, {2, 3}, {{"highway", "residential"}}},
                      {3, {3, 1}, {{"highway", "residential"}}}});
  const RoadGraph third = load_map(osm, options, &info);
  EXPECT_EQ(info.origin, MapLoadInfo::Origin::imported);
  EXPECT_EQ(third.node_count(), 3u);

  // A corrupt cache is replaced by a fresh import, not an error.
  std::filesystem::resize_file(info.cache_file, 20);
  (void)load_map(osm, options, &info);
  EXPECT_EQ(info.origin, MapLoadInfo::Origin::imported);

  // A cache file given directly as the map is read as such.
  const RoadGraph direct = load_map(info.cache_file, options, &info);
  EXPECT_EQ(info.origin, MapLoadInfo::Origin::cache);
  EXPECT_EQ(direct.node_count(), 3u);
}

// The side of the road is fixed when a cache is imported: asking a right-hand cache for left-hand
// traffic is an error, not a silent answer with the other side's turn costs.
TEST(MapLoader, ACacheKeepsTheSideOfTheRoadItWasImportedFor) {
  TempDir dir;
  const auto right = dir.path() / "right.cgr";
  write_graph_cache(right, small_grid(), {});
  MapLoadOptions left;
  left.import.left_hand_traffic = true;
  EXPECT_THROW((void)load_map(right, left), MapLoadError);
  EXPECT_FALSE(load_map(right, {}).left_hand_traffic());
  RoadGraphData d = small_grid().data();
  d.left_hand_traffic = {1};
  const auto lht = dir.path() / "left.cgr";
  write_graph_cache(lht, RoadGraph(std::move(d)), {});
  EXPECT_TRUE(load_map(lht, left).left_hand_traffic());
}

// A cache that cannot be put in place leaves no half-written file behind.
TEST(GraphCache, AFailedWriteLeavesNoTemporaryFile) {
  TempDir dir;
  const auto target = dir.path() / "taken";
  std::filesystem::create_directories(target / "inside");  // a non-empty directory: rename fails
  EXPECT_THROW(write_graph_cache(target, small_grid(), {}), GraphCacheError);
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "taken.tmp"));
}

TEST(MapLoader, MissingMapIsAClearError) {
  EXPECT_THROW((void)load_map("/no/such/map.osm.pbf", {}), MapLoadError);
}

}  // namespace
}  // namespace corridor::maps
