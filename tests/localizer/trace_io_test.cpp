// Reading traces: a GPX with no <time>, or one time for every point, is matched by geometry when
// the caller can (its fixes timed by distance at a nominal pace, and the timing reported as none)
// and refused where timing is needed; a GPX timed in part is refused either way.
#include "localizer/match/trace_io.hpp"

#include <gtest/gtest.h>

namespace corridor::localizer {
namespace {

std::string gpx(const std::vector<std::string>& times) {
  std::string s = "<gpx><trk><trkseg>";
  for (std::size_t i = 0; i < times.size(); ++i) {
    s += "<trkpt lat=\"43.7384\" lon=\"" + std::to_string(7.4246 + 0.001 * static_cast<double>(i)) + "\">";
    if (!times[i].empty()) s += "<time>" + times[i] + "</time>";
    s += "<speed>3</speed></trkpt>";
  }
  return s + "</trkseg></trk></gpx>";
}

TEST(TraceIo, AGpxWithoutTimesIsTimedByItsGeometryOrRefused) {
  const std::string untimed = gpx({"", "", ""});
  EXPECT_THROW((void)parse_gpx(untimed), TraceError);
  TraceTiming timing = TraceTiming::measured;
  const auto fixes = parse_gpx(untimed, &timing);
  EXPECT_EQ(timing, TraceTiming::none);
  ASSERT_EQ(fixes.size(), 3u);
  // 0.001° of longitude at 43.74° N is about 80 m: 8 s apart at 10 m/s.
  EXPECT_DOUBLE_EQ(fixes[0].time_s, 0.0);
  EXPECT_NEAR(fixes[1].time_s - fixes[0].time_s, 8.04, 0.1);
  EXPECT_NEAR(fixes[2].time_s - fixes[1].time_s, 8.04, 0.1);
  EXPECT_FALSE(fixes[1].speed_mps.has_value());  // a speed is no measurement without times
}

TEST(TraceIo, OneTimeForEveryPointIsNoTimingAndPartTimingIsAnError) {
  const std::string same = gpx({"2024-05-01T12:00:00Z", "2024-05-01T12:00:00Z", "2024-05-01T12:00:00Z"});
  TraceTiming timing = TraceTiming::measured;
  const auto fixes = parse_gpx(same, &timing);
  EXPECT_EQ(timing, TraceTiming::none);
  EXPECT_GT(fixes[2].time_s, fixes[0].time_s);
  EXPECT_THROW((void)parse_gpx(same), TraceError);
  try {
    (void)parse_gpx(gpx({"2024-05-01T12:00:00Z", ""}), &timing);
    FAIL() << "a trace timed in part was read";
  } catch (const TraceError& e) {
    EXPECT_NE(std::string(e.what()).find("timed throughout or not at all"), std::string::npos) << e.what();
  }
  const auto timed = parse_gpx(gpx({"2024-05-01T12:00:00Z", "2024-05-01T12:00:05Z"}), &timing);
  EXPECT_EQ(timing, TraceTiming::measured);
  EXPECT_DOUBLE_EQ(timed[1].time_s - timed[0].time_s, 5.0);
}

}  // namespace
}  // namespace corridor::localizer
