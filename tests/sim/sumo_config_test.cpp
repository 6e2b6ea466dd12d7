// Reading a user's .sumocfg as SUMO does: relative paths from the file's directory, several route
// and additional files, synonyms, H:M:S times, outputs; and a clear SimError, naming the file and
// the option, for every bad case. Also the net-version guard and additional traffic-light programs.
#include "sim/sumo_config.hpp"

#include <gtest/gtest.h>

#include <fstream>

#include "maps/sumo_net.hpp"
#include "sim/errors.hpp"
#include "tests/temp_dir.hpp"

namespace corridor::sim {
namespace {

namespace fs = std::filesystem;

class SumoConfigTest : public ::testing::Test {
 protected:
  void SetUp() override {
    fs::create_directories(dir_ / "sub");
    for (const char* f : {"sub/city.net.xml", "a.rou.xml", "b.rou.xml", "sub/tls.add.xml", "det.add.xml"}) write(f, "<x/>");
  }
  void write(const std::string& name, const std::string& text) { std::ofstream(dir_ / name) << text; }
  fs::path cfg(const std::string& body) {
    write("s.sumocfg", "<?xml version=\"1.0\"?>\n<configuration>\n" + body + "</configuration>\n");
    return dir_ / "s.sumocfg";
  }
  static std::string error_of(const fs::path& file) {
    try {
      (void)read_sumo_config(file);
    } catch (const SimError& e) {
      return e.what();
    }
    return "";
  }
  testing::TempDir tmp_{"sumocfg-test"};
  const fs::path& dir_ = tmp_.path();
};

TEST_F(SumoConfigTest, ReadsInputsRelativeToTheFileAndItsTimeWindow) {
  const auto c = read_sumo_config(cfg(
      "<input><net-file value=\"sub/city.net.xml\"/><route-files value=\"a.rou.xml, b.rou.xml\"/>"
      "<additional-files value=\"sub/tls.add.xml,det.add.xml\"/></input>"
      "<time><begin value=\"7:00:00\"/><end value=\"28800\"/></time>"
      "<output><tripinfo-output value=\"trips.xml\"/><summary-output value=\"out/summary.xml\"/></output>"
      "<report><log value=\"sumo.log\"/><verbose value=\"true\"/></report>"));
  EXPECT_EQ(c.file, fs::absolute(dir_ / "s.sumocfg").lexically_normal());
  EXPECT_EQ(c.net_file, (dir_ / "sub/city.net.xml").lexically_normal());
  ASSERT_EQ(c.route_files.size(), 2u);
  EXPECT_EQ(c.route_files[1], (dir_ / "b.rou.xml").lexically_normal());
  ASSERT_EQ(c.additional_files.size(), 2u);
  EXPECT_EQ(c.additional_files[0], (dir_ / "sub/tls.add.xml").lexically_normal());
  EXPECT_DOUBLE_EQ(c.begin_s, 25200.0);
  ASSERT_TRUE(c.end_s.has_value());
  EXPECT_DOUBLE_EQ(*c.end_s, 28800.0);
  EXPECT_EQ(c.outputs.size(), 3u);  // tripinfo, summary and log; verbose is not an output
  EXPECT_EQ(c.outputs.at("summary-output"), "out/summary.xml");
  EXPECT_TRUE(c.outputs.contains("log"));
}

TEST_F(SumoConfigTest, AcceptsSynonymsAndAbsolutePathsAndNoEnd) {
  const auto c = read_sumo_config(cfg("<n value=\"" + (dir_ / "sub/city.net.xml").string() + "\"/><r value=\"a.rou.xml\"/>"));
  EXPECT_EQ(c.net_file, (dir_ / "sub/city.net.xml").lexically_normal());
  EXPECT_EQ(c.route_files.size(), 1u);
  EXPECT_TRUE(c.additional_files.empty());
  EXPECT_DOUBLE_EQ(c.begin_s, 0.0);
  EXPECT_FALSE(c.end_s.has_value());
}

TEST_F(SumoConfigTest, EachBadCaseNamesTheFileAndTheOption) {
  EXPECT_NE(error_of(dir_ / "missing.sumocfg").find("does not exist"), std::string::npos);
  const std::string missing_route = error_of(cfg("<input><net-file value=\"sub/city.net.xml\"/>"
                                                 "<route-files value=\"a.rou.xml,gone.rou.xml\"/></input>"));
  EXPECT_NE(missing_route.find("route-files"), std::string::npos) << missing_route;
  EXPECT_NE(missing_route.find("gone.rou.xml"), std::string::npos) << missing_route;
  const std::string missing_add = error_of(cfg("<net-file value=\"sub/city.net.xml\"/><additional-files value=\"no.add.xml\"/>"));
  EXPECT_NE(missing_add.find("additional-files"), std::string::npos) << missing_add;
  EXPECT_NE(error_of(cfg("<route-files value=\"a.rou.xml\"/>")).find("no net-file"), std::string::npos);
  EXPECT_NE(error_of(cfg("<net-file value=\"sub/city.net.xml\"/><begin value=\"seven\"/>")).find("begin"), std::string::npos);
  EXPECT_NE(error_of(cfg("<net-file value=\"sub/city.net.xml\"/><begin value=\"100\"/><end value=\"50\"/>")).find("end"),
            std::string::npos);
  write("broken.sumocfg", "<configuration><input>");
  EXPECT_NE(error_of(dir_ / "broken.sumocfg").find("XML error"), std::string::npos);
}

// The user's lane-area detectors, in both of SUMO's spellings and with a lane chain, and their
// induction loops. A broken additional file is a clear error.
TEST_F(SumoConfigTest, ReadsTheLaneAreaDetectorsAndInductionLoopsOfTheAdditionalFiles) {
  write("det.add.xml",
        "<additional><laneAreaDetector id=\"q1\" lane=\"e1_0\" pos=\"0\" length=\"50\" file=\"o.xml\"/>"
        "<e2Detector id=\"q2\" lanes=\"e2_0 e3_0\" pos=\"0\" endPos=\"10\" file=\"o.xml\"/>"
        "<inductionLoop id=\"loop\" lane=\"e4_0\" pos=\"1\" file=\"o.xml\"/></additional>");
  const auto c = read_sumo_config(cfg("<net-file value=\"sub/city.net.xml\"/><additional-files value=\"det.add.xml\"/>"));
  ASSERT_EQ(c.lane_area_detectors.size(), 2u);
  EXPECT_EQ(c.lane_area_detectors[0].id, "q1");
  EXPECT_EQ(c.lane_area_detectors[0].lanes, std::vector<std::string>{"e1_0"});
  EXPECT_EQ(c.lane_area_detectors[1].id, "q2");
  EXPECT_EQ(c.lane_area_detectors[1].lanes, (std::vector<std::string>{"e2_0", "e3_0"}));
  ASSERT_EQ(c.induction_loops.size(), 1u);
  EXPECT_EQ(c.induction_loops[0].id, "loop");
  EXPECT_EQ(c.induction_loops[0].lane, "e4_0");
  EXPECT_DOUBLE_EQ(c.induction_loops[0].pos_m, 1.0);
  write("det.add.xml", "<additional><laneAreaDetector");
  EXPECT_NE(error_of(cfg("<net-file value=\"sub/city.net.xml\"/><additional-files value=\"det.add.xml\"/>")).find("det.add.xml"),
            std::string::npos);
}

TEST(SumoTime, SecondsAndClockForms) {
  EXPECT_EQ(parse_sumo_time("25200"), 25200.0);
  EXPECT_EQ(parse_sumo_time("0.5"), 0.5);
  EXPECT_EQ(parse_sumo_time("7:00:00"), 25200.0);
  EXPECT_EQ(parse_sumo_time("1:00"), 60.0);
  EXPECT_EQ(parse_sumo_time("1:2:03:04"), 86400.0 + 7200.0 + 184.0);
  for (const char* bad : {"", "x", "-1", "1:x", "1:2:3:4:5", "nan", "inf"}) EXPECT_FALSE(parse_sumo_time(bad)) << bad;
}

TEST(SumoNetVersion, NewerThanSumoIsRefusedOlderIsRead) {
  EXPECT_NO_THROW(check_net_version("n.net.xml", "1.9", "1.15.0"));
  EXPECT_NO_THROW(check_net_version("n.net.xml", "1.15", "1.15.0"));
  EXPECT_NO_THROW(check_net_version("n.net.xml", "", "1.15.0"));
  EXPECT_THROW(check_net_version("n.net.xml", "1.16", "1.15.0"), SimError);
  EXPECT_THROW(check_net_version("n.net.xml", "2.0", "1.15.0"), SimError);
  EXPECT_THROW(check_net_version("n.net.xml", "garbage", "1.15.0"), SimError);
  try {
    check_net_version("city.net.xml", "1.20", "1.15.0");
  } catch (const SimError& e) {
    EXPECT_NE(std::string(e.what()).find("city.net.xml"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("1.20"), std::string::npos);
  }
}

TEST_F(SumoConfigTest, NetVersionIsReadWithoutTheRestAndAdditionalProgramsAreRead) {
  write("v.net.xml", "<?xml version=\"1.0\"?>\n<!-- a comment with <net version=\"9.9\"> inside -->\n"
                     "<net version=\"1.16\" junctionCornerDetail=\"5\"><edge id=\"e\"/>");  // truncated after <net>
  EXPECT_EQ(maps::read_sumo_net_version(dir_ / "v.net.xml"), "1.16");
  write("old.net.xml", "<net><edge id=\"e\"/></net>");
  EXPECT_EQ(maps::read_sumo_net_version(dir_ / "old.net.xml"), "");
  write("tls.add.xml", "<additional><tlLogic id=\"J1\" programID=\"peak\" type=\"static\" offset=\"0\">"
                       "<phase duration=\"31\" state=\"GGrr\"/><phase duration=\"4\" state=\"yyrr\"/>"
                       "<phase duration=\"25\" state=\"rrGG\" minDur=\"10\"/></tlLogic></additional>");
  const auto logics = maps::read_sumo_tl_logics(dir_ / "tls.add.xml");
  ASSERT_EQ(logics.size(), 1u);
  EXPECT_EQ(logics[0].id, "J1");
  EXPECT_EQ(logics[0].program_id, "peak");
  ASSERT_EQ(logics[0].phases.size(), 3u);
  EXPECT_EQ(logics[0].phases[2].state, "rrGG");
  EXPECT_DOUBLE_EQ(logics[0].phases[2].min_duration_s, 10.0);
}

}  // namespace
}  // namespace corridor::sim
