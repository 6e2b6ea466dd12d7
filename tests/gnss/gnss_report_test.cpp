// gpsd's messages as libgps decodes them, the fixes the localizer takes from them, and the check an
// NMEA log gets before gpsd sees it. The oracles are hand-made messages with known contents.
#include <gtest/gtest.h>

#include "gnss/gnss_report.hpp"
#include "gnss/gpsd_source.hpp"
#include "gnss/nmea_replay.hpp"

namespace corridor::gnss {
namespace {

constexpr const char* kTpv3d =
    R"({"class":"TPV","device":"/dev/ttyUSB0","mode":3,"time":"2026-12-02T05:00:00.500Z",)"
    R"("lat":43.7384,"lon":7.4246,"alt":50.0,"track":91.5,"speed":12.25,"eph":38.0,"epx":15.0,"epy":22.5})";

TEST(GpsdMessage, ATpvIsDecodedWithItsModeTimePositionCourseSpeedAndErrors) {
  const auto r = decode_gpsd_message(kTpv3d);
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->mode, FixMode::three_d);
  ASSERT_TRUE(r->time_s.has_value());
  EXPECT_NEAR(*r->time_s, 1796187600.5, 1e-3);  // 2026-12-02T05:00:00.5Z
  EXPECT_DOUBLE_EQ(*r->lat_deg, 43.7384);
  EXPECT_DOUBLE_EQ(*r->lon_deg, 7.4246);
  EXPECT_DOUBLE_EQ(*r->track_deg, 91.5);
  EXPECT_DOUBLE_EQ(*r->speed_mps, 12.25);
  EXPECT_DOUBLE_EQ(*r->eph_m, 38.0);
  EXPECT_DOUBLE_EQ(*r->epy_m, 22.5);

  const auto f = to_fix(*r);
  ASSERT_TRUE(f.has_value());
  EXPECT_DOUBLE_EQ(f->hdop.value(), 38.0 / kGpsdEphPerHdop);
  EXPECT_DOUBLE_EQ(f->heading_deg.value(), 91.5);
  EXPECT_DOUBLE_EQ(f->speed_mps.value(), 12.25);
}

TEST(GpsdMessage, OtherClassesAndWhatLibgpsCannotReadAreNotReports) {
  EXPECT_FALSE(decode_gpsd_message(R"({"class":"SKY","device":"/dev/ttyUSB0","hdop":1.2})").has_value());
  EXPECT_FALSE(decode_gpsd_message(R"({"class":"VERSION","release":"3.22","rev":"3.22","proto_major":3,"proto_minor":14})").has_value());
  EXPECT_FALSE(decode_gpsd_message("").has_value());
  EXPECT_FALSE(decode_gpsd_message("{\"class\":\"TPV\",\"mode\":").has_value());
  EXPECT_FALSE(decode_gpsd_message("not json at all\n").has_value());
  // libgps 3.22's parser never returns on this one (found by gnss_fuzzer): it must not reach it.
  EXPECT_FALSE(decode_gpsd_message(R"({"class":"TPV""class":"TPV")").has_value());
}

TEST(GpsdMessage, SpeedWithoutAFixIsRefusedWithTheReason) {
  const auto r = decode_gpsd_message(R"({"class":"TPV","mode":1,"time":"2026-12-02T05:00:01.000Z","speed":9.0})");
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->mode, FixMode::none);
  std::string why;
  EXPECT_FALSE(to_fix(*r, &why).has_value());
  EXPECT_EQ(why, "no 2D/3D fix");
}

TEST(GnssFix, ErrorsFromEpxEpyWhenThereIsNoEphAndNoCourseAtWalkingPace) {
  GnssReport r;
  r.mode = FixMode::two_d;
  r.time_s = 100.0;
  r.lat_deg = 43.7;
  r.lon_deg = 7.4;
  r.epx_m = 30.0;
  r.epy_m = 45.0;
  r.speed_mps = 0.4;
  r.track_deg = 270.0;
  const auto f = to_fix(r);
  ASSERT_TRUE(f.has_value());
  EXPECT_DOUBLE_EQ(f->hdop.value(), 45.0 / kGpsdEpxyPerDop);
  EXPECT_FALSE(f->heading_deg.has_value());
}

TEST(GnssFix, APositionOffTheEarthOrWithoutTimeIsRefused) {
  GnssReport r;
  r.mode = FixMode::three_d;
  r.time_s = 100.0;
  r.lat_deg = 91.0;
  r.lon_deg = 7.4;
  std::string why;
  EXPECT_FALSE(to_fix(r, &why).has_value());
  EXPECT_EQ(why, "no valid position");
  r.lat_deg = 43.0;
  r.time_s.reset();
  EXPECT_FALSE(to_fix(r, &why).has_value());
  EXPECT_EQ(why, "no time");
}

TEST(NmeaLog, SentencesBadChecksumsAndOtherLinesAreCounted) {
  // The first sentence's checksum is right (0x68), the second's is not; then a garbage line.
  const auto c = check_nmea_log(
      "$GPGGA,050000.00,4344.304,N,00725.476,E,1,08,0.9,50.0,M,0.0,M,,*68\r\n"
      "$GPRMC,050000.00,A,4344.304,N,00725.476,E,23.8,91.5,021226,,,A*00\r\n"
      "\r\n"
      "garbage 123\n");
  EXPECT_EQ(c.lines, 3u);
  EXPECT_EQ(c.sentences, 2u);
  EXPECT_EQ(c.other, 1u);
  EXPECT_EQ(c.bad_checksums, 1u);
}

}  // namespace
}  // namespace corridor::gnss
