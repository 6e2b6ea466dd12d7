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

// By the file's content: GPX when it starts with '<', CSV otherwise. Throws TraceError for a
// missing or empty file, malformed XML or CSV, a point without a time, a coordinate that is not
// one, and times that decrease.
std::vector<GpsFix> read_trace(const std::filesystem::path& file);
std::vector<GpsFix> parse_gpx(const std::string& text);
std::vector<GpsFix> parse_csv(const std::string& text);

// ISO 8601 UTC time ("2024-05-01T12:00:03Z", fractional seconds and ±hh:mm offsets allowed) as
// Unix seconds. Throws TraceError.
double parse_iso8601(const std::string& s);

}  // namespace corridor::localizer
