// The HMM map matcher against hand-built cases where nearest-road snapping goes wrong (a parallel
// service road, an overpass, a U-turn, a roundabout), its breaks (a gap, nothing near), bad input,
// and, as an oracle, noiseless and noisy drives along random routes whose true edges are known.
#include "localizer/match/hmm_matcher.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <limits>
#include <numbers>
#include <random>
#include <string>

#include "localizer/match/synthetic_trace.hpp"
#include "tests/localizer/sketch_graph.hpp"
#include "maps/synthetic_grid.hpp"
#include "planner/route.hpp"

namespace corridor::localizer {
namespace {

using testing::Sketch;

GpsFix fix_at(const maps::RoadGraph& g, double t, maps::Point2 p, std::optional<double> heading = {},
              std::optional<double> speed = {}) {
  return {t, g.projection().to_lat_lon(p), 1.0, heading, speed};
}

std::int64_t way_of(const maps::RoadGraph& g, const MatchedPoint& m) { return m.matched ? g.osm_way(m.edge).v : -1; }

// One two-way road of 2 km, west to east along y = 0 (way 1).
struct StraightRoad {
  maps::RoadGraph g = testing::straight_road(2000.0);
  maps::EdgeSnapper snapper{g};
};

// The trace fed fix by fix to an online matcher: what it reports after each.
std::vector<MatchedPoint> match_online(const maps::RoadGraph& g, const maps::EdgeSnapper& snapper,
                                       const std::vector<GpsFix>& trace, const HmmConfig& config = {}) {
  HmmMatcher online(g, snapper, config);
  std::vector<MatchedPoint> live;
  for (const GpsFix& f : trace) live.push_back(online.update(f));
  return live;
}

// A main road with a service road 12 m beside it, joined at both ends. Fixes along the main road
// drift 7 m towards the service road, nearer to it than to the main road for half the drive: a
// nearest-road snap jumps across; the HMM stays, since the jump would need a route through the
// joins far longer than the fixes moved.
TEST(HmmMatcher, StaysOnTheMainRoadBesideAParallelServiceRoad) {
  Sketch s;
  s.nodes = {{0, 0}, {100, 0}, {900, 0}, {1000, 0}, {100, 12}, {900, 12}};
  s.roads = {{{0, 1, 2, 3}, false, 1}, {{1, 4}, false, 2}, {{4, 5}, false, 3}, {{5, 2}, false, 2}};
  const auto g = s.build();
  const maps::EdgeSnapper snapper(g);
  HmmMatcher matcher(g, snapper);
  std::vector<GpsFix> trace;
  for (int i = 0; i <= 60; ++i) {
    const double x = 50.0 + i * 15.0;
    const double y = (i % 2 == 0) ? 7.0 : 3.0;  // every other fix is nearer the service road
    trace.push_back(fix_at(g, i * 1.0, {x, y}, 90.0, 15.0));
  }
  int on_main = 0, nearest_on_main = 0;
  for (const MatchedPoint& m : matcher.match(trace)) on_main += way_of(g, m) == 1 ? 1 : 0;
  for (const GpsFix& f : trace) nearest_on_main += g.osm_way(snapper.snap(f.position).edge).v == 1 ? 1 : 0;
  EXPECT_EQ(on_main, 61);
  EXPECT_LT(nearest_on_main, 61);  // the case is hard for the snap
  // Online too, one fix at a time.
  HmmMatcher online(g, snapper);
  int online_main = 0;
  for (const GpsFix& f : trace) online_main += way_of(g, online.update(f)) == 1 ? 1 : 0;
  EXPECT_GE(online_main, 58);
}

// Road 1 runs east; road 2 crosses it on a bridge with no junction. Fixes where they cross are as
// near to one as to the other; the HMM keeps the vehicle on the road it was driving.
TEST(HmmMatcher, KeepsTheRoadThroughAnOverpass) {
  Sketch s;
  s.nodes = {{0, 0}, {1000, 0}, {500, -500}, {500, 500}};
  s.roads = {{{0, 1}, false, 1}, {{2, 3}, false, 2}};
  const auto g = s.build();
  const maps::EdgeSnapper snapper(g);
  HmmMatcher matcher(g, snapper);
  std::vector<GpsFix> trace;
  std::mt19937_64 rng(3);
  std::normal_distribution<double> noise(0.0, 4.0);
  for (int i = 0; i <= 50; ++i) trace.push_back(fix_at(g, i, {250.0 + i * 10.0 + noise(rng), noise(rng)}));
  for (const MatchedPoint& m : matcher.match(trace)) EXPECT_EQ(way_of(g, m), 1);
}

// East along a two-way street, then back west: the direction of travel flips with the U-turn.
TEST(HmmMatcher, FollowsAUTurnOnATwoWayStreet) {
  Sketch s;
  s.nodes = {{0, 0}, {400, 0}, {800, 0}};
  s.roads = {{{0, 1, 2}, false, 1}};
  const auto g = s.build();
  const maps::EdgeSnapper snapper(g);
  HmmMatcher matcher(g, snapper);
  std::vector<GpsFix> trace;
  for (int i = 0; i <= 20; ++i) trace.push_back(fix_at(g, i, {100.0 + i * 20.0, 2.0}, 90.0, 20.0));
  for (int i = 1; i <= 20; ++i) trace.push_back(fix_at(g, 20 + i, {500.0 - i * 20.0, 2.0}, 270.0, 20.0));
  const auto matched = matcher.match(trace);
  auto heading_east = [&](const MatchedPoint& m) { return g.position(g.head(m.edge)).x_m > g.position(g.tail(m.edge)).x_m; };
  for (int i = 0; i <= 18; ++i) {
    ASSERT_TRUE(matched[static_cast<std::size_t>(i)].matched) << i;
    EXPECT_TRUE(heading_east(matched[static_cast<std::size_t>(i)])) << i;
  }
  // The turn is mid-block, where the graph has no way round: the chain breaks there and the
  // westward one starts within four fixes of it.
  bool restarted = false;
  for (std::size_t i = 19; i <= 24; ++i) restarted = restarted || (matched[i].matched && matched[i].chain_start);
  EXPECT_TRUE(restarted);
  for (std::size_t i = 24; i < matched.size(); ++i) {
    ASSERT_TRUE(matched[i].matched) << i;
    EXPECT_FALSE(heading_east(matched[i])) << i;
  }
}

// A one-way roundabout (radius 30 m, counter-clockwise) with four arms: the vehicle enters from the
// west and leaves by the east arm; every fix on the ring is matched to the ring, in its direction.
TEST(HmmMatcher, GoesRoundARoundabout) {
  Sketch s;
  const int ring = 12;
  for (int k = 0; k < ring; ++k) {
    const double a = std::numbers::pi + 2.0 * std::numbers::pi * k / ring;  // from the west, counter-clockwise seen from above
    s.nodes.push_back({30.0 * std::cos(-a), 30.0 * std::sin(-a)});
  }
  Sketch::Road r{{}, true, 9};
  for (int k = 0; k <= ring; ++k) r.through.push_back(static_cast<std::uint32_t>(k % ring));
  s.roads.push_back(r);
  const auto arm = [&](std::uint32_t ring_node, maps::Point2 far, std::int64_t way) {
    s.nodes.push_back(far);
    s.roads.push_back({{static_cast<std::uint32_t>(s.nodes.size() - 1), ring_node}, false, way});
  };
  arm(0, {-300, 0}, 1);
  arm(3, {0, -300}, 2);
  arm(6, {300, 0}, 3);
  arm(9, {0, 300}, 4);
  const auto g = s.build();
  const maps::EdgeSnapper snapper(g);
  HmmMatcher matcher(g, snapper);
  std::vector<GpsFix> trace;
  double t = 0;
  for (double x = -250; x <= -40; x += 15) trace.push_back(fix_at(g, t++, {x, 1.5}));
  // Half way round, through the south (the ring's node 3) to the east (node 6).
  for (int k = 1; k < 6; ++k) {
    const double a = std::numbers::pi + 2.0 * std::numbers::pi * (k + 0.5) / ring;
    trace.push_back(fix_at(g, t++, {31.0 * std::cos(-a), 31.0 * std::sin(-a)}));
  }
  for (double x = 45; x <= 250; x += 15) trace.push_back(fix_at(g, t++, {x, -1.5}));
  const auto matched = matcher.match(trace);
  std::vector<std::int64_t> ways;
  for (const auto& m : matched) {
    if (ways.empty() || ways.back() != way_of(g, m)) ways.push_back(way_of(g, m));
  }
  EXPECT_EQ(ways, (std::vector<std::int64_t>{1, 9, 3}));
  // The east arm is driven outward.
  EXPECT_GT(g.position(g.head(matched.back().edge)).x_m, g.position(g.tail(matched.back().edge)).x_m);
}

TEST(HmmMatcher, AGapOrNothingNearBreaksTheChainAndItRestarts) {
  const StraightRoad road;
  const maps::RoadGraph& g = road.g;
  const maps::EdgeSnapper& snapper = road.snapper;
  HmmMatcher matcher(g, snapper);
  std::vector<GpsFix> trace;
  for (int i = 0; i < 5; ++i) trace.push_back(fix_at(g, i, {100.0 + i * 10, 1.0}));
  trace.push_back(fix_at(g, 5, {150, 900}));            // nothing within reach
  trace.push_back(fix_at(g, 6, {160, 1.0}));            // online: starts a new chain
  trace.push_back(fix_at(g, 300, {170, 1.0}));          // a 294 s gap
  trace.push_back(fix_at(g, 301, {180, 1.0}));
  for (int i = 0; i < 3; ++i) trace.push_back(fix_at(g, 302 + i, {190.0 + i * 10, 900}));  // nothing, three times
  trace.push_back(fix_at(g, 305, {220, 1.0}));                                           // a new chain
  trace.push_back(fix_at(g, 306, {230, 1.0}));
  const auto m = matcher.match(trace);
  EXPECT_TRUE(m[0].chain_start);
  EXPECT_FALSE(m[4].chain_start);
  // Batch: one fix with nothing near, between fixes that fit, is a multipath outlier, set aside
  // and placed on the road by its neighbours, not a break.
  EXPECT_TRUE(m[5].matched && m[5].outlier);
  EXPECT_NEAR(m[5].point.x_m, 150.0, 3.0);
  EXPECT_TRUE(m[6].matched && !m[6].chain_start && !m[6].outlier);
  EXPECT_TRUE(m[7].matched && m[7].chain_start);
  EXPECT_TRUE(m[8].matched && !m[8].chain_start);
  // More than max_skipped such fixes in a row break the chain.
  for (int i = 9; i <= 11; ++i) EXPECT_FALSE(m[static_cast<std::size_t>(i)].matched) << i;
  EXPECT_TRUE(m[12].matched && m[12].chain_start);
  EXPECT_TRUE(m[13].matched && !m[13].chain_start);
  // Online, which must answer at once, breaks at the first.
  const auto live = match_online(g, snapper, trace);
  EXPECT_FALSE(live[5].matched);
  EXPECT_TRUE(live[6].chain_start);
  EXPECT_TRUE(live[7].chain_start);
  EXPECT_FALSE(live[8].chain_start);
}

// A 90 s gap (a tunnel) between fixes on one road is no break: the move across it is checked
// against the straight line, not against the one speed the fix after it reports. That fix was
// taken standing in a queue; its speed × 90 s says 0 m were driven, where 860 m were.
TEST(HmmMatcher, LinksAcrossAGapOfMinutesWithoutTrustingOneFixsSpeed) {
  const StraightRoad road;
  const maps::RoadGraph& g = road.g;
  const maps::EdgeSnapper& snapper = road.snapper;
  std::vector<GpsFix> trace;
  for (int i = 0; i < 5; ++i) trace.push_back(fix_at(g, i, {100.0 + i * 10, 1.0}, 90.0, 10.0));
  trace.push_back(fix_at(g, 94, {1000, 1.0}, 90.0, 0.0));
  trace.push_back(fix_at(g, 95, {1000, 1.0}, 90.0, 0.0));
  const auto m = HmmMatcher(g, snapper).match(trace);
  ASSERT_TRUE(m[5].matched);
  EXPECT_FALSE(m[5].chain_start);
  const auto live = match_online(g, snapper, trace);
  ASSERT_TRUE(live[5].matched);
  EXPECT_FALSE(live[5].chain_start);
  // A gap longer than gap_s still breaks the chain.
  HmmConfig short_gap;
  short_gap.gap_s = 60.0;
  EXPECT_TRUE(HmmMatcher(g, snapper, short_gap).match(trace)[5].chain_start);
}

// The vehicle leaves the main road (way 1) by a link the map lacks, onto a road 20 m beside it
// (way 2) that the map joins to the main road only 2 km further on. No move reaches way 2 from the
// fixes before; the main road is reached, and each fix is only 20 m (3.3σ) from it. Without a
// fresh start the chain stays glued to the main road for as long as the vehicle drives beside it.
TEST(HmmMatcher, StartsAfreshWhereTheVehicleDroveOffTheMap) {
  Sketch s;
  s.nodes = {{0, 0}, {3000, 0}, {3000, 20}, {300, 20}};
  s.roads = {{{0, 1}, false, 1}, {{1, 2, 3}, false, 2}};
  const auto g = s.build();
  const maps::EdgeSnapper snapper(g);
  std::vector<GpsFix> trace;
  for (int i = 0; i < 30; ++i) trace.push_back(fix_at(g, i, {10.0 * i, 0.5}, 90.0, 10.0));           // x = 0 … 290
  for (int i = 0; i < 30; ++i) trace.push_back(fix_at(g, 31 + i, {310.0 + 10.0 * i, 20.5}, 90.0, 10.0));  // beside it
  const auto m = HmmMatcher(g, snapper).match(trace);
  for (std::size_t i = 0; i < 25; ++i) EXPECT_EQ(way_of(g, m[i]), 1) << i;
  for (std::size_t i = 35; i < m.size(); ++i) EXPECT_EQ(way_of(g, m[i]), 2) << i;
  bool restarted = false;
  for (std::size_t i = 28; i < 36; ++i) restarted = restarted || m[i].chain_start;
  EXPECT_TRUE(restarted);
  const auto live = match_online(g, snapper, trace);
  for (std::size_t i = 40; i < live.size(); ++i) EXPECT_EQ(way_of(g, live[i]), 2) << i;
  // Online, the fix where way 2 first becomes the best is flagged: no route joins it to the
  // point reported before, though its path started afresh some fixes earlier.
  std::size_t flagged = 0;
  for (std::size_t i = 1; i < live.size(); ++i) {
    if (!live[i].chain_start) continue;
    ++flagged;
    EXPECT_EQ(way_of(g, live[i]), 2) << i;
    EXPECT_EQ(way_of(g, live[i - 1]), 1) << i;
  }
  EXPECT_EQ(flagged, 1u);
  // Never starting afresh, both stay on the main road.
  HmmConfig never;
  never.restart_penalty = std::numeric_limits<double>::infinity();
  EXPECT_EQ(way_of(g, HmmMatcher(g, snapper, never).match(trace).back()), 1);
  EXPECT_EQ(way_of(g, match_online(g, snapper, trace, never).back()), 1);
}

// A multipath fix lands on the top of a block beside the main road, where a drive round the block
// could just reach it between two fixes. The path round it, less the price of one outlier, beats
// the detour: the fix is set aside and placed on the main road where the vehicle was.
TEST(HmmMatcher, SetsAsideAMultipathFixThatOnlyADetourCouldReach) {
  Sketch s;
  s.nodes = {{0, 0}, {500, 0}, {560, 0}, {1200, 0}, {500, 40}, {560, 40}};
  s.roads = {{{0, 1, 2, 3}, false, 1}, {{1, 4, 5, 2}, false, 2}};
  const auto g = s.build();
  const maps::EdgeSnapper snapper(g);
  std::vector<GpsFix> trace;
  for (int i = 0; i <= 12; ++i) {
    const double x = 300.0 + i * 50.0;  // 10 m/s, a fix every 5 s
    trace.push_back(fix_at(g, i * 5.0, i == 5 ? maps::Point2{530, 40} : maps::Point2{x, 0.5}, 90.0, 10.0));
  }
  const auto m = HmmMatcher(g, snapper).match(trace);
  EXPECT_TRUE(m[5].matched && m[5].outlier);
  EXPECT_EQ(way_of(g, m[5]), 1);
  EXPECT_NEAR(m[5].point.x_m, 550.0, 10.0);
  for (std::size_t i = 0; i < m.size(); ++i) {
    EXPECT_EQ(way_of(g, m[i]), 1) << i;
    if (i != 5) {
      EXPECT_FALSE(m[i].outlier) << i;
    }
  }
  // Without the price of an outlier (never worth it), the matcher drives round the block.
  HmmConfig never;
  never.outlier_penalty = 1e9;
  EXPECT_EQ(way_of(g, HmmMatcher(g, snapper, never).match(trace)[5]), 2);
}

// A fix 28 m off the only road (7σ): following it costs its emission, not its moves, which fit.
// Skip arcs weigh the whole path through it, on one scale across steps, against the price of an
// outlier: it is set aside (a comparison of the moves alone would keep it).
TEST(HmmMatcher, SetsAsideAFixFarFromTheRoadEvenWhenItsMovesFit) {
  const StraightRoad road;
  const maps::RoadGraph& g = road.g;
  const maps::EdgeSnapper& snapper = road.snapper;
  std::vector<GpsFix> trace;
  for (int i = 0; i <= 12; ++i) trace.push_back(fix_at(g, i * 5.0, {300.0 + i * 50.0, i == 5 ? 28.0 : 0.5}, 90.0, 10.0));
  const auto m = HmmMatcher(g, snapper).match(trace);
  EXPECT_TRUE(m[5].matched && m[5].outlier);
  EXPECT_NEAR(m[5].point.x_m, 550.0, 5.0);
  for (std::size_t i = 0; i < m.size(); ++i) {
    if (i != 5) {
      EXPECT_TRUE(m[i].matched && !m[i].outlier) << i;
    }
  }
}

// A service road (way 2) drawn 3 m beside its street (way 1), joined at both ends. The fixes run
// between them, 1.2 m from the service road and 1.8 m from the street: the emissions favour the
// service road (by 0.7 over the drive), by less than the price of entering it, so the street
// keeps the match. A vehicle that does turn into
// a service road, 30 m off, is followed onto it all the same.
TEST(HmmMatcher, AServiceRoadBesideItsStreetPaysToEnter) {
  Sketch s;
  s.nodes = {{0, 0}, {100, 0}, {400, 0}, {600, 0}, {110, 3}, {390, 3}, {450, 0}, {450, 30}, {600, 30}};
  s.roads = {{{0, 1, 2, 6, 3}, false, 1},
             {{1, 4, 5, 2}, false, 2, maps::RoadClass::service},
             {{6, 7, 8}, false, 3, maps::RoadClass::service}};
  const auto g = s.build();
  const maps::EdgeSnapper snapper(g);
  std::vector<GpsFix> beside;
  for (int i = 0; i <= 40; ++i) {
    const double x = 10.0 * i;  // 10 m/s east, to x = 400
    beside.push_back(fix_at(g, i, {x, x > 110.0 && x < 390.0 ? 1.8 : 0.0}, 90.0, 10.0));
  }
  const auto m = HmmMatcher(g, snapper).match(beside);
  for (std::size_t i = 0; i < m.size(); ++i) EXPECT_EQ(way_of(g, m[i]), 1) << i;
  HmmConfig free_entry;
  free_entry.service_entry_penalty = 0.0;
  EXPECT_EQ(way_of(g, HmmMatcher(g, snapper, free_entry).match(beside)[25]), 2);
  // Into the service road at x = 450 and along it, 30 m north of the street.
  std::vector<GpsFix> into;
  for (int i = 0; i <= 44; ++i) into.push_back(fix_at(g, i, {10.0 * i, 0.0}, 90.0, 10.0));  // to x = 440
  for (int i = 1; i <= 3; ++i) into.push_back(fix_at(g, 44 + i, {450, 10.0 * i}, 0.0, 10.0));
  for (int i = 1; i <= 10; ++i) into.push_back(fix_at(g, 47 + i, {450.0 + 10.0 * i, 30.0}, 90.0, 10.0));
  const auto in = HmmMatcher(g, snapper).match(into);
  for (std::size_t i = in.size() - 10; i < in.size(); ++i) EXPECT_EQ(way_of(g, in[i]), 3) << i;
}

// A vehicle waits 5 m before a junction; its fixes scatter by σ 5 m, some of them well behind
// the one before (more than a fixed tolerance of 8 m). Standing still is the explanation, not a
// U-turn or the side street: every fix stays on the approach, in the direction it came.
TEST(HmmMatcher, AVehicleWaitingAtAJunctionStaysOnItsApproach) {
  Sketch s;
  s.nodes = {{0, 0}, {200, 0}, {400, 0}, {200, 25}, {200, -150}};
  s.roads = {{{0, 1, 2}, false, 1}, {{3, 1, 4}, false, 2}};
  const auto g = s.build();
  const maps::EdgeSnapper snapper(g);
  std::vector<GpsFix> trace;
  for (int i = 0; i < 15; ++i) trace.push_back(fix_at(g, i, {50.0 + i * 10.0, 0.0}, 90.0, 10.0));
  std::mt19937_64 rng(11);
  std::normal_distribution<double> noise(0.0, 5.0);
  int behind = 0;
  double last_x = 190.0;
  for (int i = 15; i < 60; ++i) {
    const maps::Point2 p{195.0 + noise(rng), noise(rng)};
    behind += p.x_m < last_x - 8.0 ? 1 : 0;
    last_x = p.x_m;
    GpsFix f = fix_at(g, i, p, std::nullopt, 0.0);
    f.hdop = 1.25;  // σ 5 m with the default base of 4 m
    trace.push_back(f);
  }
  ASSERT_GE(behind, 3);  // the case needs fixes well behind the last
  auto on_approach = [&](const MatchedPoint& m) {
    return m.matched && g.osm_way(m.edge).v == 1 && g.position(g.tail(m.edge)).x_m < g.position(g.head(m.edge)).x_m;
  };
  const auto batch = HmmMatcher(g, snapper).match(trace);
  for (std::size_t i = 15; i < batch.size(); ++i) EXPECT_TRUE(on_approach(batch[i])) << i;
  // Online, each answer is the best guess at once, before the next fix can show that a jump onto
  // the side street was noise: most, not all.
  HmmMatcher online(g, snapper);
  int online_on = 0;
  for (const GpsFix& f : trace) online_on += on_approach(online.update(f)) ? 1 : 0;
  EXPECT_GE(online_on, 15 + 40);
}

// A fork: the trunk runs east, then road 2 goes on east and road 3 leaves 20° to its left. The
// vehicle keeps east on road 2, its course saying so, while its fixes (σ 12 m) drift north, four
// fifths of the way towards road 3 and so nearer to it, for the 75 m after the fork. Both roads
// lead on from the fork and the moves fit either, so only the course tells them apart. In the
// heading mixture 20° off a road costs 1.7 (log-likelihood), more than the up to 1.6 that a fix's
// distances give road 3; one Gaussian wide enough for turns (σ 40°) charges 0.1, so it follows
// the fixes onto the wrong branch, which is what this case is for.
TEST(HmmMatcher, TheCourseTellsTheBranchesOfAShallowForkApart) {
  Sketch s;
  const double fork_deg = 20.0, rad = fork_deg * std::numbers::pi / 180.0;
  s.nodes = {{0, 0}, {300, 0}, {800, 0}, {300 + 500 * std::cos(rad), 500 * std::sin(rad)}};
  s.roads = {{{0, 1}, false, 1}, {{1, 2}, false, 2}, {{1, 3}, false, 3}};
  const auto g = s.build();
  const maps::EdgeSnapper snapper(g);
  std::vector<GpsFix> trace;
  for (int i = 0; i <= 19; ++i) {
    const double x = 90.0 + 15.0 * i, past = std::max(0.0, x - 300.0);
    GpsFix f = fix_at(g, i, {x, 0.8 * past * std::tan(rad)}, 90.0, 15.0);
    f.hdop = 3.0;
    trace.push_back(f);
  }
  auto on_road_2_after_the_fork = [&](const std::vector<MatchedPoint>& matched, const char* how) {
    for (std::size_t i = 0; i < trace.size(); ++i) {
      if (g.projection().to_local(trace[i].position).x_m < 322.5) continue;  // the fork's first 30 m may go either way
      EXPECT_EQ(way_of(g, matched[i]), 2) << how << " fix " << i;
    }
  };
  HmmMatcher batch(g, snapper);
  on_road_2_after_the_fork(batch.match(trace), "batch");
  const auto live = match_online(g, snapper, trace);
  on_road_2_after_the_fork(live, "online");
  // The case is hard for a single wide Gaussian in the course.
  HmmMatcher wide(g, snapper, HmmConfig{.heading_sigma_deg = 40.0, .heading_wide_share = 0.0});
  const auto by_wide = wide.match(trace);
  for (std::size_t i = 17; i < trace.size(); ++i) EXPECT_EQ(way_of(g, by_wide[i]), 3) << "single Gaussian, fix " << i;
  // All the weight on the wide part is the same single Gaussian.
  HmmMatcher all_wide(g, snapper, HmmConfig{.heading_wide_share = 1.0});
  EXPECT_EQ(way_of(g, all_wide.match(trace).back()), 3);
  EXPECT_THROW(HmmMatcher(g, snapper, HmmConfig{.heading_wide_share = 1.5}), std::invalid_argument);
  EXPECT_THROW(HmmMatcher(g, snapper, HmmConfig{.heading_sigma_deg = std::numeric_limits<double>::infinity()}),
               std::invalid_argument);
}

TEST(HmmMatcher, RejectsUnsortedTimesAndNonFiniteFixes) {
  const auto g = testing::straight_road(500.0);
  const maps::EdgeSnapper snapper(g);
  HmmMatcher matcher(g, snapper);
  std::vector<GpsFix> unsorted{fix_at(g, 5, {10, 0}), fix_at(g, 4, {20, 0})};
  EXPECT_THROW(matcher.match(unsorted), std::invalid_argument);
  GpsFix nan = fix_at(g, 1, {10, 0});
  nan.position.lat_deg = std::nan("");
  EXPECT_THROW(matcher.update(nan), std::invalid_argument);
  EXPECT_THROW(HmmMatcher(g, snapper, HmmConfig{.beta_m = 0.0}), std::invalid_argument);
  // A trace entirely off the map matches nothing, without error.
  const std::vector<GpsFix> far{fix_at(g, 0, {0, 5000}), fix_at(g, 1, {10, 5000})};
  for (const auto& m : matcher.match(far)) EXPECT_FALSE(m.matched);
}

// Oracle: drives along random shortest routes of random grids, one fix a second at 12 m/s, with
// Gaussian noise of σ 5 m. The matched edge must be the driven one for nearly every fix, and far
// more often than the nearest road is.
TEST(HmmMatcher, RecoversTheDrivenEdgesOfRandomRoutes) {
  std::size_t total = 0, correct = 0, nearest_correct = 0;
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    maps::GridSpec spec;
    spec.rows = 10;
    spec.cols = 10;
    spec.seed = seed;
    spec.spacing_m = 150.0;
    const auto g = maps::make_perturbed_grid(spec);
    const maps::EdgeSnapper snapper(g);
    HmmMatcher matcher(g, snapper);
    SyntheticTraceSpec drive;
    drive.seed = seed;
    drive.noise_sigma_m = 5.0;
    const SyntheticTrace t = make_synthetic_trace(g, drive);
    const std::vector<GpsFix>& trace = t.fixes;
    const std::vector<EdgeId>& truth = t.truth;
    const auto matched = matcher.match(trace);
    for (std::size_t i = 0; i < trace.size(); ++i) {
      ++total;
      correct += matched[i].matched && matched[i].edge == truth[i] ? 1 : 0;
      nearest_correct += snapper.snap(trace[i].position).edge == truth[i] ? 1 : 0;
    }
  }
  ASSERT_GT(total, 500u);
  const double share = static_cast<double>(correct) / static_cast<double>(total);
  const double nearest = static_cast<double>(nearest_correct) / static_cast<double>(total);
  std::cout << "hmm correct " << share << " nearest " << nearest << " over " << total << " fixes\n";
  EXPECT_GE(share, 0.95) << "correct " << correct << " of " << total;
  EXPECT_GT(share, nearest + 0.1) << "nearest-road snap " << nearest;
}

}  // namespace
}  // namespace corridor::localizer
