// Reads position traces: GPX (track, route or waypoints, parsed with expat) or CSV with
// `time,lat,lon[,hdop,heading_deg,speed_mps]`. Every bad input is a TraceError naming the line or
// point, never a guess.
#pragma once

#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "localizer/match/gps_fix.hpp"

namespace corridor::localizer {

class TraceError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Whether a trace says when its fixes were taken. Common GPX exports carry no <time> at all, or
// one time for every point; such a trace can only be matched by its geometry, as GraphHopper does.
enum class TraceTiming { measured, none };

// The times given to an untimed trace's fixes: their distance along the trace at this pace, so
// that a matcher's speed checks see a plausible drive. Nothing else reads them.
inline constexpr double kUntimedPaceMps = 10.0;

// By the file's content: GPX when it starts with '<', CSV otherwise. Throws TraceError for a
// missing or empty file, malformed XML or CSV, a coordinate that is not one, times that decrease,
// and points of which some have a time and some not. A trace with no timing (no point has a time,
// or all have the same) is a TraceError where `timing` is null; otherwise it is read, its fixes
// timed by kUntimedPaceMps, and *timing says so.
std::vector<GpsFix> read_trace(const std::filesystem::path& file, TraceTiming* timing = nullptr);
std::vector<GpsFix> parse_gpx(const std::string& text, TraceTiming* timing = nullptr);
std::vector<GpsFix> parse_csv(const std::string& text);

// ISO 8601 UTC time ("2024-05-01T12:00:03Z", fractional seconds and ±hh:mm offsets allowed) as
// Unix seconds. Throws TraceError.
double parse_iso8601(const std::string& s);

}  // namespace corridor::localizer
