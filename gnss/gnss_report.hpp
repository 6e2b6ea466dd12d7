// A receiver's report as gpsd gives it (its TPV: mode, time, position, course, speed and error
// estimates), and how a report becomes a fix the localizer takes: only with a 2D or 3D fix, and
// with gpsd's horizontal error estimate turned into the HDOP the matchers' accuracy model reads.
#pragma once

#include <optional>
#include <string>

#include "localizer/match/gps_fix.hpp"

namespace corridor::gnss {

enum class FixMode { not_seen = 0, none = 1, two_d = 2, three_d = 3 };

struct GnssReport {
  FixMode mode = FixMode::not_seen;
  std::optional<double> time_s;  // Unix seconds, from the receiver's own clock
  std::optional<double> lat_deg, lon_deg;
  std::optional<double> track_deg;   // course over ground, true north
  std::optional<double> speed_mps;   // over ground
  std::optional<double> eph_m;       // horizontal error estimate (gpsd: HDOP x 19 m, ~95 %)
  std::optional<double> epx_m, epy_m;  // longitude and latitude error estimates
};

// gpsd's horizontal error estimate per unit of HDOP (gpsd 3.22's UERE for eph, no DGPS): the
// factor that turns its eph back into the HDOP the localizer's σ model was calibrated with.
inline constexpr double kGpsdEphPerHdop = 19.0;
// gpsd's epx/epy per unit of xdop/ydop.
inline constexpr double kGpsdEpxyPerDop = 15.0;
// Below this speed a receiver's course is noise.
inline constexpr double kMinCourseSpeedMps = 1.0;

// The fix, or nullopt with the reason in *why: no 2D/3D mode, no time, or a position that is not one.
[[nodiscard]] std::optional<localizer::GpsFix> to_fix(const GnssReport& report, std::string* why = nullptr);

}  // namespace corridor::gnss
