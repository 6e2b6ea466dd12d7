#include "gnss/gnss_report.hpp"

#include <algorithm>
#include <cmath>

namespace corridor::gnss {
namespace {

bool finite(const std::optional<double>& v) { return v && std::isfinite(*v); }

}  // namespace

std::optional<localizer::GpsFix> to_fix(const GnssReport& r, std::string* why) {
  const auto refuse = [&](const char* reason) -> std::optional<localizer::GpsFix> {
    if (why != nullptr) *why = reason;
    return std::nullopt;
  };
  if (r.mode != FixMode::two_d && r.mode != FixMode::three_d) return refuse("no 2D/3D fix");
  if (!finite(r.time_s) || *r.time_s <= 0.0) return refuse("no time");
  if (!finite(r.lat_deg) || !finite(r.lon_deg) || !maps::is_valid_lat_lon({*r.lat_deg, *r.lon_deg})) return refuse("no valid position");
  localizer::GpsFix f;
  f.time_s = *r.time_s;
  f.position = {*r.lat_deg, *r.lon_deg};
  // The HDOP the matchers' σ model reads: gpsd's eph divided by its own factor; from epx and epy
  // where it gave no eph.
  if (finite(r.eph_m) && *r.eph_m > 0.0) {
    f.hdop = *r.eph_m / kGpsdEphPerHdop;
  } else if (finite(r.epx_m) && finite(r.epy_m) && *r.epx_m > 0.0 && *r.epy_m > 0.0) {
    f.hdop = std::max(*r.epx_m, *r.epy_m) / kGpsdEpxyPerDop;
  }
  if (finite(r.speed_mps) && *r.speed_mps >= 0.0) f.speed_mps = *r.speed_mps;
  if (finite(r.track_deg) && f.speed_mps && *f.speed_mps >= kMinCourseSpeedMps) {
    f.heading_deg = std::fmod(std::fmod(*r.track_deg, 360.0) + 360.0, 360.0);
  }
  return f;
}

}  // namespace corridor::gnss
