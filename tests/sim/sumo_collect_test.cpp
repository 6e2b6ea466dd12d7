// Collecting run records into the experiment's tables: each run is paired with the baseline of its
// demand and seed, the median and IQR come out of the records, every run is a row (a failed one
// with its status and reason, one without a baseline without others' delay), the headline compares
// strategies over the same seeds, and records of two scenarios are refused.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>

#include "sim/errors.hpp"
#include "sim/sumo_experiment.hpp"
#include "tests/temp_dir.hpp"

namespace corridor::sim {
namespace {

namespace fs = std::filesystem;

class SumoCollectTest : public ::testing::Test {
 protected:
  void SetUp() override { fs::create_directories(dir_ / "runs" / "a"); }

  static RunRecord identity(bool with_ev, EvSignals signals, std::uint64_t seed, const std::string& scenario = "town",
                            EvRouting routing = EvRouting::dynamic_route) {
    RunRecord r;
    r.scenario = scenario;
    r.with_ev = with_ev;
    r.routing = routing;
    r.signals = signals;
    r.demand_scale = 1.5;
    r.seed = seed;
    r.ev_depart_s = 100.0;
    return r;
  }
  void add(const std::string& name, bool with_ev, EvSignals signals, std::uint64_t seed, double travel, double others_loss,
           const std::string& scenario = "town", EvRouting routing = EvRouting::dynamic_route) {
    RunRecord r;
    r.scenario = scenario;
    r.with_ev = with_ev;
    r.routing = routing;
    r.signals = signals;
    r.demand_scale = 1.5;
    r.seed = seed;
    r.ev_depart_s = 100.0;
    r.result.ev_arrived = true;
    r.result.ev_travel_time_s = travel;
    r.result.others_mean_time_loss_s = others_loss;
    r.result.end_time_s = 900.0;
    std::ofstream(dir_ / "runs" / "a" / (name + ".run.json")) << to_json_record(r).dump();
  }
  std::string read(const std::string& name) {
    std::ifstream in(dir_ / "out" / name);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  }
  testing::TempDir tmp_{"sumo-collect"};
  const fs::path& dir_ = tmp_.path();
};

TEST_F(SumoCollectTest, PairsBaselinesAndSummarizesMediansAndIqr) {
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    add("b" + std::to_string(seed), false, EvSignals::none, seed, 0.0, 50.0);
    add("c" + std::to_string(seed), true, EvSignals::corridor, seed, 100.0 * seed, 50.0 + seed);
  }
  const auto rows = collect_sumo_experiment({dir_ / "runs"}, dir_ / "out").rows;
  ASSERT_EQ(rows.size(), 3u);
  ASSERT_TRUE(rows[1].baseline_time_loss_s.has_value());
  EXPECT_DOUBLE_EQ(*rows[1].baseline_time_loss_s, 50.0);
  EXPECT_NEAR(rows[1].others_delay_rel(), 2.0 / 50.0, 1e-12);
  // Median 200, quartiles 150 and 250 (linear interpolation), 3 of 3 arrived.
  EXPECT_NE(read("sumo_summary.csv").find("dynamic,corridor,0,3,3,200.0,150.0,250.0"), std::string::npos)
      << read("sumo_summary.csv");
  EXPECT_NE(read("sumo_summary.md").find("demand x1.5"), std::string::npos);
  const std::string runs = read("sumo_runs.csv");
  EXPECT_EQ(std::count(runs.begin(), runs.end(), '\n'), 4);
}

TEST_F(SumoCollectTest, UnreadableRecordsAreListedAndAnUnpairedRunKeepsItsRow) {
  add("b1", false, EvSignals::none, 1, 0.0, 40.0);
  add("c1", true, EvSignals::corridor, 1, 120.0, 41.0);
  add("c2", true, EvSignals::corridor, 2, 130.0, 41.0);  // seed 2 has no baseline
  std::ofstream(dir_ / "runs" / "a" / "crashed.run.json") << R"({"error": "SUMO connection lost"})";
  std::ofstream(dir_ / "runs" / "a" / "half.run.json") << R"({"scenario": "town", "with_)";
  auto files = std::vector<fs::path>{};
  for (const auto& e : fs::directory_iterator(dir_ / "runs" / "a")) files.push_back(e.path());
  files.push_back(dir_ / "runs" / "a" / "aborted.run.json");  // planned, but its process died
  const auto tables = collect_run_files(files, dir_ / "out");
  ASSERT_EQ(tables.rows.size(), 2u);
  EXPECT_EQ(tables.rows[0].run.seed, 1u);
  EXPECT_EQ(tables.rows[1].run.seed, 2u);
  EXPECT_FALSE(tables.rows[1].baseline_time_loss_s.has_value());
  EXPECT_TRUE(std::isnan(tables.rows[1].others_delay_rel()));
  EXPECT_EQ(tables.failures.size(), 4u);
  const std::string md = read("sumo_summary.md");
  EXPECT_NE(md.find("4 run(s) did not complete"), std::string::npos) << md;
  EXPECT_NE(md.find("aborted.run.json: no result"), std::string::npos) << md;
  EXPECT_NE(md.find("SUMO connection lost"), std::string::npos);
  EXPECT_NE(md.find("no run without the EV"), std::string::npos);
  // The unpaired run's others' delay is empty, not a zero that reads as a result.
  const std::string runs = read("sumo_runs.csv");
  EXPECT_NE(runs.find("dynamic,corridor,0,2,130.0,0,0.0,0,,"), std::string::npos) << runs;
}

// A run that failed is a row with status failed and its reason; its cell says how many failed; a
// run the matrix planned that left no record at all is a failed row too; and the headline compares
// medians over the seeds where every compared strategy completed.
TEST_F(SumoCollectTest, EveryPlannedRunIsARowAndTheHeadlineIsPaired) {
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    const std::string k = std::to_string(seed);
    add("b" + k, false, EvSignals::none, seed, 0.0, 50.0);
    add("none" + k, true, EvSignals::none, seed, 300.0 + seed, 50.0, "town", EvRouting::static_route);
    add("blue" + k, true, EvSignals::bluelight, seed, 250.0 + seed, 50.0, "town", EvRouting::static_route);
  }
  // The corridor strategy completes seed 1, fails seed 2 with SUMO's reason, and never wrote seed 3.
  add("c1", true, EvSignals::corridor, 1, 100.0, 51.0);
  write_record(dir_ / "runs" / "a" / "c2.run.json",
               failed_run(identity(true, EvSignals::corridor, 2), "Vehicle 'ev' has no valid route, \"am90\" to am91"));
  const nlohmann::json matrix{{"runs", {{{"file", "a/c3.run.json"}, {"identity", to_json_record(identity(true, EvSignals::corridor, 3))}}}}};
  std::ofstream(dir_ / "runs" / "matrix.json") << matrix.dump();

  const auto tables = collect_sumo_experiment({dir_ / "runs"}, dir_ / "out");
  ASSERT_EQ(tables.rows.size(), 9u);  // 3 seeds x 3 strategies: none vanishes
  std::size_t failed = 0;
  for (const auto& row : tables.rows) failed += row.ok() ? 0 : 1;
  EXPECT_EQ(failed, 2u);
  EXPECT_EQ(tables.failures.size(), 2u);
  const std::string runs = read("sumo_runs.csv");
  EXPECT_NE(runs.find(",failed,\"Vehicle 'ev' has no valid route, \"\"am90\"\" to am91\",\n"), std::string::npos) << runs;
  EXPECT_NE(runs.find("c3.run.json: no result"), std::string::npos) << runs;
  EXPECT_EQ(std::count(runs.begin(), runs.end(), '\n'), 10);
  const std::string md = read("sumo_summary.md");
  EXPECT_NE(md.find("n=1, **2 of 3 failed**"), std::string::npos) << md;
  // Seed 1 alone: corridor 100 s against static/none 301 s and static/bluelight 251 s.
  EXPECT_NE(md.find("dynamic / corridor 100 s; -66.8% against static / none (301 s), -60.2% against static / bluelight (251 s); "
                    "over 1 of 3 seeds (**the others did not complete**)"),
            std::string::npos)
      << md;
  const std::string summary = read("sumo_summary.csv");
  EXPECT_NE(summary.find("dynamic,corridor,0,1,1,100.0,100.0,100.0"), std::string::npos) << summary;
  EXPECT_NE(summary.find(",1.5,3,2\n"), std::string::npos) << summary;  // planned 3, failed 2
}

TEST_F(SumoCollectTest, RefusesMixedScenariosAndNothingToCollect) {
  EXPECT_THROW(collect_sumo_experiment({dir_ / "runs"}, dir_ / "out"), SimError);
  EXPECT_THROW(collect_sumo_experiment({dir_ / "nowhere"}, dir_ / "out"), SimError);
  add("b1", false, EvSignals::none, 1, 0.0, 40.0, "town");
  add("c1", true, EvSignals::corridor, 1, 120.0, 41.0, "city");
  EXPECT_THROW(collect_sumo_experiment({dir_ / "runs"}, dir_ / "out"), SimError);
}

TEST(RunRecord, RoundTripsAndRejectsWhatIsNotOne) {
  RunRecord r;
  r.scenario = "x";
  r.signals = EvSignals::corridor_bluelight;
  r.routing = EvRouting::static_route;
  r.volume = 400.0;
  r.seed = 7;
  r.result.ev_stops = 2;
  const RunRecord back = record_from_json(to_json_record(r), "mem");
  EXPECT_EQ(back.signals, EvSignals::corridor_bluelight);
  EXPECT_EQ(back.routing, EvRouting::static_route);
  EXPECT_EQ(back.seed, 7u);
  EXPECT_EQ(back.result.ev_stops, 2);
  EXPECT_EQ(to_json_record(r)["signals"], "corridor+bluelight");
  auto j = to_json_record(r);
  j["signals"] = "sirens";
  EXPECT_THROW(record_from_json(j, "mem"), SimError);
  EXPECT_THROW(record_from_json(nlohmann::json::array(), "mem"), SimError);
  EXPECT_THROW(record_from_json(nlohmann::json{{"scenario", 3}}, "mem"), SimError);
  // A failed run keeps its identity and its reason.
  const RunRecord failed = record_from_json(to_json_record(failed_run(r, "SUMO refused the route")), "mem");
  EXPECT_EQ(failed.status, RunStatus::failed);
  EXPECT_EQ(failed.failure, "SUMO refused the route");
  EXPECT_EQ(failed.seed, 7u);
  EXPECT_EQ(to_json_record(failed_run(r, "x"))["status"], "failed");
}

}  // namespace
}  // namespace corridor::sim
