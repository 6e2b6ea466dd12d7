#include "planner/experiments/analytical_experiments.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "maps/map_loader.hpp"

namespace corridor::planner {
namespace {

std::string read(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

class AnalyticalExperiments : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("corridor_analytical_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    std::filesystem::remove_all(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::filesystem::path dir_;
};

TEST_F(AnalyticalExperiments, SameSeedWritesTheSameCsvByteForByteWhateverTheThreadCount) {
  const auto g = *builtin_analytical_graph("complex");
  AnalyticalOptions o;
  o.level_runs = 20;
  o.out_dir = dir_ / "one";
  o.threads = 1;
  const auto first = run_graph_experiments(g, o);
  o.out_dir = dir_ / "two";
  o.threads = 3;
  run_graph_experiments(g, o);
  o.out_dir = dir_ / "other";
  o.seed = 2;
  run_graph_experiments(g, o);
  ASSERT_EQ(first.size(), 5u);  // fig6, fig7, fig8a, fig8b, fig9
  for (const auto& r : first) {
    for (const auto& f : r.files) {
      const std::string a = read(f);
      ASSERT_FALSE(a.empty()) << f;
      EXPECT_EQ(a, read(dir_ / "two" / f.filename())) << f.filename();
      if (f.extension() == ".csv" && f.string().find("summary") == std::string::npos) {
        EXPECT_NE(a, read(dir_ / "other" / f.filename())) << "seed has no effect on " << f.filename();
      }
    }
  }
}

TEST_F(AnalyticalExperiments, Fig5ReproducesThePapersConclusionsOnTheSimpleGraph) {
  const auto g = *builtin_analytical_graph("simple");
  AnalyticalOptions o;
  o.level_runs = 50;
  o.out_dir = dir_;
  const auto reports = run_graph_experiments(g, o);
  ASSERT_EQ(reports.size(), 1u);
  EXPECT_EQ(reports[0].experiment, "fig5");
  const auto& s = reports[0].summaries;
  ASSERT_EQ(s.size(), 8u * 4u);
  auto at = [&](int level, int strategy) { return s[static_cast<std::size_t>(level * 4 + strategy)]; };
  // No congestion: static equals dynamic, with and without preemption.
  EXPECT_DOUBLE_EQ(at(0, 0).median_travel_s, at(0, 1).median_travel_s);
  EXPECT_DOUBLE_EQ(at(0, 2).median_travel_s, at(0, 3).median_travel_s);
  for (int level = 0; level < 8; ++level) {
    // Dynamic is never worse than static here, and dynamic + preemption is the best.
    EXPECT_LE(at(level, 1).median_travel_s, at(level, 0).median_travel_s + 1e-9);
    EXPECT_LE(at(level, 3).median_travel_s, at(level, 2).median_travel_s + 1e-9);
    for (int k = 0; k < 3; ++k) EXPECT_LE(at(level, 3).median_travel_s, at(level, k).median_travel_s + 1e-9);
  }
  // Static grows with the queue delay (two jammed links on its corridor: 2 min per level) ...
  EXPECT_NEAR(at(7, 0).median_travel_s - at(0, 0).median_travel_s, 7 * 2 * 60.0, 1e-3);
  // ... while dynamic levels off once the other corridor is cheaper.
  EXPECT_NEAR(at(7, 1).median_travel_s, at(4, 1).median_travel_s, 1e-9);
  EXPECT_NEAR(at(7, 3).median_travel_s, at(1, 3).median_travel_s, 1e-9);
  for (const char* f : {"simple_fig5.csv", "simple_fig5_summary.csv", "simple_fig5.svg"}) {
    EXPECT_TRUE(std::filesystem::exists(dir_ / f)) << f;
  }
  const std::string csv = read(dir_ / "simple_fig5.csv");
  EXPECT_EQ(csv.substr(0, csv.find('\n')),
            "experiment,run,level_min,source,destination,base_s,routing,signals,travel_s,increase_pct,signal_wait_s,"
            "queue_wait_s,events,replans,route_changes,rerouted,expanded");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 1 + 50 * 8 * 4);
}

TEST_F(AnalyticalExperiments, MapProtocolRunsOnMonacoWithRoutingStatistics) {
  const maps::RoadGraph monaco = maps::load_map(CORRIDOR_DEFAULT_MAP, {});
  AnalyticalOptions o;
  o.pairs = 40;
  o.out_dir = dir_;
  const auto reports = run_map_experiments(monaco, "monaco", o);
  ASSERT_EQ(reports.size(), 4u);  // levels, fig7, fig8b, fig9
  for (const auto& r : reports) {
    for (const auto& s : r.summaries) {
      EXPECT_GT(s.runs, 0u);
      EXPECT_GE(s.median_increase_pct, -1e-9) << r.experiment << ": nothing beats the uncongested, unsignalled base";
    }
  }
  const auto& fig7 = reports[1].summaries;
  EXPECT_EQ(fig7[1].runs, 40u);
  EXPECT_GT(fig7[1].replans, 0u);
  EXPECT_GT(fig7[1].rerouted, 0u);
  EXPECT_LE(fig7[1].route_changes, fig7[1].replans);
  const std::string md = render_markdown(reports);
  EXPECT_NE(md.find("### monaco fig7"), std::string::npos);
  EXPECT_NE(md.find("worse than static"), std::string::npos);
}

TEST_F(AnalyticalExperiments, RejectsZeroRunsAndAMissingOutputDirectory) {
  const auto g = *builtin_analytical_graph("simple");
  AnalyticalOptions o;
  EXPECT_THROW(run_graph_experiments(g, o), std::invalid_argument);
  o.out_dir = dir_;
  o.level_runs = 0;
  EXPECT_THROW(run_graph_experiments(g, o), std::invalid_argument);
}

}  // namespace
}  // namespace corridor::planner
