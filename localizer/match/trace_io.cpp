#include "localizer/match/trace_io.hpp"

#include <expat.h>

#include <cctype>
#include <charconv>
#include <cmath>
#include <ctime>
#include <cstdio>
#include <iomanip>
#include <algorithm>
#include <fstream>
#include <memory>
#include <optional>
#include <sstream>

namespace corridor::localizer {
namespace {

std::string trim(std::string s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.pop_back();
  std::size_t b = 0;
  while (b < s.size() && std::isspace(static_cast<unsigned char>(s[b]))) ++b;
  return s.substr(b);
}

std::optional<double> to_number(const std::string& s) {
  const std::string t = trim(s);
  if (t.empty()) return std::nullopt;
  double v = 0;
  const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
  if (ec != std::errc() || end != t.data() + t.size() || !std::isfinite(v)) return std::nullopt;
  return v;
}

void check_order(const std::vector<GpsFix>& fixes, const char* what) {
  if (fixes.empty()) throw TraceError(std::string("the trace has no ") + what);
  for (std::size_t i = 1; i < fixes.size(); ++i) {
    if (fixes[i].time_s < fixes[i - 1].time_s) {
      throw TraceError(std::string(what) + " " + std::to_string(i + 1) + " is earlier than the one before it: times must not decrease");
    }
  }
}

// The GPX elements a fix reads; anything else (extensions, names) is skipped.
struct GpxParser {
  std::vector<GpsFix> fixes;
  std::optional<GpsFix> current;
  bool current_has_time = false;
  std::size_t timed = 0, untimed = 0;
  std::size_t first_untimed = 0, first_timed = 0;  // their point numbers, for the message
  std::string text;
  std::string error;
  std::size_t points = 0;

  static std::string local_name(const char* name) {
    std::string n(name);
    const auto colon = n.rfind(':');
    return colon == std::string::npos ? n : n.substr(colon + 1);
  }

  void start(const char* name, const char** attrs) {
    text.clear();
    const std::string n = local_name(name);
    if (n != "trkpt" && n != "rtept" && n != "wpt") return;
    ++points;
    std::optional<double> lat, lon;
    for (int i = 0; attrs[i] != nullptr; i += 2) {
      const std::string key(attrs[i]);
      if (key == "lat") lat = to_number(attrs[i + 1]);
      if (key == "lon") lon = to_number(attrs[i + 1]);
    }
    if (!lat || !lon || !maps::is_valid_lat_lon({*lat, *lon})) {
      fail("GPX point " + std::to_string(points) + " has no valid lat and lon attributes");
      return;
    }
    current = GpsFix{};
    current->position = {*lat, *lon};
    current_has_time = false;
  }

  void end(const char* name) {
    const std::string n = local_name(name);
    if (current) {
      const std::string value = trim(text);
      if (n == "time") {
        try {
          current->time_s = parse_iso8601(value);
          current_has_time = true;
        } catch (const TraceError& e) {
          fail("GPX point " + std::to_string(points) + ": " + e.what());
        }
      } else if (n == "hdop") {
        current->hdop = to_number(value);
      } else if (n == "course") {
        current->heading_deg = to_number(value);
      } else if (n == "speed") {
        current->speed_mps = to_number(value);
      } else if (n == "trkpt" || n == "rtept" || n == "wpt") {
        if (current_has_time) {
          if (timed++ == 0) first_timed = points;
        } else if (untimed++ == 0) {
          first_untimed = points;
        }
        fixes.push_back(*current);
        current.reset();
      }
    }
    text.clear();
  }

  void fail(std::string why) {
    if (error.empty()) error = std::move(why);
  }
};

}  // namespace

double parse_iso8601(const std::string& s) {
  std::tm tm{};
  std::istringstream in(s);
  in >> std::get_time(&tm, "%Y-%m-%dT%H:%M:%S");
  if (in.fail()) throw TraceError("time '" + s.substr(0, 40) + "' is not ISO 8601 (YYYY-MM-DDThh:mm:ss[.fff][Z|±hh:mm])");
  double seconds = static_cast<double>(timegm(&tm));
  std::string rest;
  std::getline(in, rest);
  std::size_t i = 0;
  if (i < rest.size() && rest[i] == '.') {
    std::size_t j = i + 1;
    while (j < rest.size() && std::isdigit(static_cast<unsigned char>(rest[j]))) ++j;
    seconds += std::stod("0" + rest.substr(i, j - i));
    i = j;
  }
  if (i < rest.size() && (rest[i] == '+' || rest[i] == '-')) {
    const int sign = rest[i] == '+' ? 1 : -1;
    int hh = 0, mm = 0;
    if (std::sscanf(rest.c_str() + i + 1, "%2d:%2d", &hh, &mm) != 2) {
      throw TraceError("time '" + s.substr(0, 40) + "' has an unreadable UTC offset");
    }
    seconds -= sign * (hh * 3600.0 + mm * 60.0);
    i += 6;
  } else if (i < rest.size() && (rest[i] == 'Z' || rest[i] == 'z')) {
    ++i;
  }
  if (i != rest.size()) throw TraceError("time '" + s.substr(0, 40) + "' has trailing characters");
  return seconds;
}

std::vector<GpsFix> parse_gpx(const std::string& text, TraceTiming* timing) {
  std::unique_ptr<XML_ParserStruct, decltype(&XML_ParserFree)> parser(XML_ParserCreate(nullptr), &XML_ParserFree);
  if (!parser) throw TraceError("cannot create an XML parser");
  GpxParser gpx;
  XML_SetUserData(parser.get(), &gpx);
  XML_SetElementHandler(
      parser.get(), [](void* self, const char* name, const char** attrs) { static_cast<GpxParser*>(self)->start(name, attrs); },
      [](void* self, const char* name) { static_cast<GpxParser*>(self)->end(name); });
  XML_SetCharacterDataHandler(parser.get(), [](void* self, const char* s, int len) {
    auto* p = static_cast<GpxParser*>(self);
    if (p->text.size() < 4096) p->text.append(s, static_cast<std::size_t>(len));
  });
  if (XML_Parse(parser.get(), text.data(), static_cast<int>(text.size()), 1) == XML_STATUS_ERROR) {
    throw TraceError("the GPX is not well-formed XML: " + std::string(XML_ErrorString(XML_GetErrorCode(parser.get()))) +
                     " at line " + std::to_string(XML_GetCurrentLineNumber(parser.get())));
  }
  if (!gpx.error.empty()) throw TraceError(gpx.error);
  if (gpx.timed > 0 && gpx.untimed > 0) {
    throw TraceError("GPX point " + std::to_string(gpx.first_untimed) + " has no <time>, but point " + std::to_string(gpx.first_timed) +
                     " has one: a trace is timed throughout or not at all");
  }
  // No time at all, or one time for every point (an export that stamped the file, not the fixes).
  const bool all_same = gpx.fixes.size() > 1 && std::all_of(gpx.fixes.begin(), gpx.fixes.end(), [&](const GpsFix& f) {
                          return f.time_s == gpx.fixes.front().time_s;
                        });
  if (gpx.untimed > 0 || all_same) {
    if (gpx.fixes.empty()) throw TraceError("the trace has no GPX points");
    if (timing == nullptr) {
      throw TraceError(gpx.untimed > 0 ? "GPX point " + std::to_string(gpx.first_untimed) + " has no <time>: this needs when each fix was taken"
                                       : std::string("every GPX point has the same <time>: this needs when each fix was taken"));
    }
    *timing = TraceTiming::none;
    // Timed by distance at a nominal pace, from the first point's time (0 where it had none).
    const double start = gpx.untimed > 0 ? 0.0 : gpx.fixes.front().time_s;
    const maps::LocalProjection frame(gpx.fixes.front().position);
    double t = start;
    for (std::size_t i = 0; i < gpx.fixes.size(); ++i) {
      if (i > 0) {
        const double step_m = maps::distance_m(frame.to_local(gpx.fixes[i - 1].position), frame.to_local(gpx.fixes[i].position));
        t += std::max(1.0, step_m / kUntimedPaceMps);
      }
      gpx.fixes[i].time_s = t;
      gpx.fixes[i].speed_mps.reset();  // a speed without times is not one this trace measured
    }
    return gpx.fixes;
  }
  if (timing != nullptr) *timing = TraceTiming::measured;
  check_order(gpx.fixes, "GPX points");
  return gpx.fixes;
}

std::vector<GpsFix> parse_csv(const std::string& text) {
  std::istringstream in(text);
  std::string line;
  std::vector<std::string> columns{"time", "lat", "lon", "hdop", "heading_deg", "speed_mps"};
  std::vector<GpsFix> fixes;
  std::size_t line_no = 0;
  bool first = true;
  while (std::getline(in, line)) {
    ++line_no;
    line = trim(line);
    if (line.empty() || line[0] == '#') continue;
    std::vector<std::string> fields;
    std::stringstream ss(line);
    for (std::string f; std::getline(ss, f, ',');) fields.push_back(trim(f));
    if (first) {
      first = false;
      if (!to_number(fields[0])) {  // a header names the columns
        columns = fields;
        for (const char* need : {"time", "lat", "lon"}) {
          if (std::find(columns.begin(), columns.end(), need) == columns.end()) {
            throw TraceError(std::string("CSV header has no '") + need + "' column (expected time,lat,lon[,hdop,heading_deg,speed_mps])");
          }
        }
        continue;
      }
    }
    if (fields.size() < 3) throw TraceError("CSV line " + std::to_string(line_no) + " needs at least time,lat,lon");
    GpsFix f;
    std::optional<double> lat, lon, time;
    for (std::size_t c = 0; c < fields.size() && c < columns.size(); ++c) {
      const auto v = to_number(fields[c]);
      const std::string& name = columns[c];
      if (!v && !fields[c].empty() && (name == "time" || name == "lat" || name == "lon" || name == "hdop" ||
                                       name == "heading_deg" || name == "speed_mps")) {
        throw TraceError("CSV line " + std::to_string(line_no) + ": " + name + " '" + fields[c].substr(0, 40) + "' is not a finite number");
      }
      if (name == "time") time = v;
      if (name == "lat") lat = v;
      if (name == "lon") lon = v;
      if (name == "hdop") f.hdop = v;
      if (name == "heading_deg") f.heading_deg = v;
      if (name == "speed_mps") f.speed_mps = v;
    }
    if (!time || !lat || !lon) throw TraceError("CSV line " + std::to_string(line_no) + " lacks time, lat or lon");
    f.time_s = *time;
    f.position = {*lat, *lon};
    if (!maps::is_valid_lat_lon(f.position)) {
      throw TraceError("CSV line " + std::to_string(line_no) + ": lat must be in [-90, 90] and lon in [-180, 180]");
    }
    fixes.push_back(f);
  }
  check_order(fixes, "CSV rows");
  return fixes;
}

std::vector<GpsFix> read_trace(const std::filesystem::path& file, TraceTiming* timing) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw TraceError("trace file not found: '" + file.string() + "'");
  std::ostringstream all;
  all << in.rdbuf();
  const std::string text = all.str();
  const std::string head = trim(text.substr(0, 256));
  if (head.empty()) throw TraceError("trace file '" + file.string() + "' is empty");
  if (head[0] == '<') return parse_gpx(text, timing);
  if (timing != nullptr) *timing = TraceTiming::measured;
  return parse_csv(text);
}

}  // namespace corridor::localizer
