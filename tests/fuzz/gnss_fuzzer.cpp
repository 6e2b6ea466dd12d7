// libFuzzer target for what receivers send: a gpsd JSON message as libgps decodes it for
// corridor localize --gpsd, and a recorded NMEA log's check before --nmea replays it. A report
// either becomes a fix with a valid position, time and non-negative speed and HDOP, or is refused
// with a reason. An exception, a crash or a sanitizer report is a finding.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "gnss/gnss_report.hpp"
#include "gnss/gpsd_source.hpp"
#include "gnss/nmea_replay.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace corridor::gnss;
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const NmeaLogCheck c = check_nmea_log(text);
    if (c.sentences + c.other != c.lines || c.bad_checksums > c.sentences) std::abort();
    if (const auto report = decode_gpsd_message(text)) {
      std::string why;
      if (const auto fix = to_fix(*report, &why)) {
        if (!std::isfinite(fix->time_s) || !corridor::maps::is_valid_lat_lon(fix->position)) std::abort();
        if (fix->hdop && !(std::isfinite(*fix->hdop) && *fix->hdop > 0.0)) std::abort();
        if (fix->speed_mps && !(std::isfinite(*fix->speed_mps) && *fix->speed_mps >= 0.0)) std::abort();
        if (fix->heading_deg && !(*fix->heading_deg >= 0.0 && *fix->heading_deg < 360.0)) std::abort();
      } else if (why.empty()) {
        std::abort();
      }
    }
  } catch (...) {
    std::abort();
  }
  return 0;
}
