#include "sim/sumo_config.hpp"

#include <expat.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <regex>
#include <sstream>

#include "sim/errors.hpp"

namespace corridor::sim {
namespace {

struct ConfigParse {
  std::vector<std::string> sections;  // element names from the root down
  std::vector<std::pair<std::string, std::string>> options;
  std::map<std::string, std::string> section_of;
};

void on_start(void* user, const char* name, const char** attrs) {
  auto& st = *static_cast<ConfigParse*>(user);
  for (const char** a = attrs; *a != nullptr; a += 2) {
    if (std::strcmp(a[0], "value") == 0) {
      st.options.emplace_back(name, a[1]);
      st.section_of[name] = st.sections.empty() ? "" : st.sections.back();
    }
  }
  st.sections.emplace_back(name);
}

void on_end(void* user, const char*) { static_cast<ConfigParse*>(user)->sections.pop_back(); }

// SUMO's synonyms for the options Corridor reads.
std::string canonical(const std::string& name) {
  if (name == "n" || name == "net") return "net-file";
  if (name == "r" || name == "routes") return "route-files";
  if (name == "a" || name == "additional") return "additional-files";
  if (name == "b") return "begin";
  if (name == "e") return "end";
  return name;
}

bool is_output_option(const std::string& name, const std::string& section) {
  return section == "output" || name.ends_with("-output") || name.ends_with("-dump") || name == "log" ||
         name == "message-log" || name == "error-log";
}

std::pair<int, int> major_minor(const std::string& version) {
  static const std::regex re(R"((\d+)\.(\d+))");
  std::smatch m;
  if (!std::regex_search(version, m, re)) return {-1, -1};
  return {std::stoi(m[1].str()), std::stoi(m[2].str())};
}

// Runs expat over `text` with these handlers: the error ("line N: message") when it is not XML.
std::optional<std::string> parse_xml(const std::string& text, void* user, XML_StartElementHandler start, XML_EndElementHandler end) {
  std::unique_ptr<XML_ParserStruct, decltype(&XML_ParserFree)> parser(XML_ParserCreate(nullptr), &XML_ParserFree);
  XML_SetUserData(parser.get(), user);
  XML_SetElementHandler(parser.get(), start, end);
  if (XML_Parse(parser.get(), text.data(), static_cast<int>(text.size()), 1) != XML_STATUS_ERROR) return std::nullopt;
  return "line " + std::to_string(XML_GetCurrentLineNumber(parser.get())) + ": " + XML_ErrorString(XML_GetErrorCode(parser.get()));
}

struct DetectorParse {
  std::vector<LaneAreaDetector> detectors;
  std::vector<InductionLoop> loops;
};

void on_detector(void* user, const char* name, const char** attrs) {
  auto& st = *static_cast<DetectorParse*>(user);
  if (std::strcmp(name, "inductionLoop") == 0 || std::strcmp(name, "e1Detector") == 0) {
    InductionLoop loop;
    for (const char** a = attrs; *a != nullptr; a += 2) {
      if (std::strcmp(a[0], "id") == 0) loop.id = a[1];
      if (std::strcmp(a[0], "lane") == 0) loop.lane = a[1];
      if (std::strcmp(a[0], "pos") == 0) loop.pos_m = std::strtod(a[1], nullptr);
    }
    if (!loop.id.empty() && !loop.lane.empty() && std::isfinite(loop.pos_m)) st.loops.push_back(std::move(loop));
    return;
  }
  if (std::strcmp(name, "laneAreaDetector") != 0 && std::strcmp(name, "e2Detector") != 0) return;
  LaneAreaDetector d;
  for (const char** a = attrs; *a != nullptr; a += 2) {
    if (std::strcmp(a[0], "id") == 0) d.id = a[1];
    if (std::strcmp(a[0], "lane") == 0) d.lanes = {a[1]};
    if (std::strcmp(a[0], "lanes") == 0) {
      std::istringstream in(a[1]);
      d.lanes.clear();
      for (std::string lane; in >> lane;) d.lanes.push_back(lane);
    }
  }
  if (!d.id.empty() && !d.lanes.empty()) st.detectors.push_back(std::move(d));
}

// The e2 and e1 detectors of one additional file; SUMO itself reports a malformed file when it
// loads it.
DetectorParse read_detectors(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  DetectorParse st;
  if (const auto error = parse_xml(text, &st, on_detector, nullptr)) {
    throw SimError("additional file '" + file.string() + "' is not valid XML: " + *error);
  }
  return st;
}

}  // namespace

std::optional<double> parse_sumo_time(const std::string& text) {
  if (text.empty() || text.size() > 64) return std::nullopt;
  std::vector<double> fields;
  std::size_t start = 0;
  while (true) {
    const auto colon = text.find(':', start);
    const std::string part = text.substr(start, colon == std::string::npos ? std::string::npos : colon - start);
    std::size_t used = 0;
    double v = 0.0;
    try {
      v = std::stod(part, &used);
    } catch (const std::exception&) {
      return std::nullopt;
    }
    if (used != part.size() || !std::isfinite(v) || v < 0.0) return std::nullopt;
    fields.push_back(v);
    if (colon == std::string::npos) break;
    start = colon + 1;
  }
  if (fields.size() > 4) return std::nullopt;
  // From the right: seconds, minutes, hours, days.
  constexpr std::array<double, 4> unit{1.0, 60.0, 3600.0, 86400.0};
  double total = 0.0;
  for (std::size_t i = 0; i < fields.size(); ++i) total += fields[fields.size() - 1 - i] * unit[i];
  return total;
}

SumoConfig read_sumo_config(const std::filesystem::path& file) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec)) {
    throw SimError("scenario '" + file.string() + "' does not exist (expected a SUMO .sumocfg file)");
  }
  std::ifstream in(file, std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (!in.good() && !in.eof()) throw SimError("cannot read '" + file.string() + "'");

  ConfigParse st;
  if (const auto error = parse_xml(text, &st, on_start, on_end)) {
    throw SimError("'" + file.string() + "' is not a valid SUMO configuration: XML error at " + *error);
  }

  SumoConfig c;
  c.file = std::filesystem::absolute(file).lexically_normal();
  const auto base = c.file.parent_path();
  const auto resolve = [&](const std::string& option, const std::string& value) {
    std::filesystem::path p(value);
    if (p.is_relative()) p = base / p;
    p = p.lexically_normal();
    if (!std::filesystem::is_regular_file(p, ec)) {
      throw SimError("'" + file.string() + "': " + option + " names '" + value + "', which does not exist (looked for " +
                     p.string() + ")");
    }
    return p;
  };
  const auto time = [&](const std::string& option, const std::string& value) {
    const auto t = parse_sumo_time(value);
    if (!t) throw SimError("'" + file.string() + "': " + option + " must be a time in seconds or H:M:S, got '" + value + "'");
    return *t;
  };
  for (const auto& [raw_name, value] : st.options) {
    c.options.push_back({raw_name, value});
    const std::string name = canonical(raw_name);
    if (name == "net-file") {
      c.net_file = resolve(name, value);
    } else if (name == "route-files") {
      c.route_files.clear();
      for (const auto& item : split_files(value)) c.route_files.push_back(resolve(name, item));
    } else if (name == "additional-files") {
      c.additional_files.clear();
      for (const auto& item : split_files(value)) c.additional_files.push_back(resolve(name, item));
    } else if (name == "begin") {
      c.begin_s = time(name, value);
    } else if (name == "end") {
      c.end_s = time(name, value);
    } else if (is_output_option(name, st.section_of[raw_name]) && !value.empty()) {
      c.outputs[name] = value;
    }
  }
  if (c.net_file.empty()) throw SimError("'" + file.string() + "' names no net-file: a scenario needs its network");
  for (const auto& additional : c.additional_files) {
    DetectorParse found = read_detectors(additional);
    for (auto& d : found.detectors) c.lane_area_detectors.push_back(std::move(d));
    for (auto& l : found.loops) c.induction_loops.push_back(std::move(l));
  }
  if (c.end_s && *c.end_s <= c.begin_s) {
    throw SimError("'" + file.string() + "': end must come after begin");
  }
  return c;
}

std::string installed_sumo_version(const std::string& binary) {
  const std::string command = binary + " --version 2>/dev/null";
  std::unique_ptr<FILE, int (*)(FILE*)> pipe(popen(command.c_str(), "r"), &pclose);
  if (!pipe) throw SimError("cannot run '" + binary + " --version'");
  std::string out;
  std::array<char, 256> buf{};
  while (std::fgets(buf.data(), buf.size(), pipe.get()) != nullptr) out += buf.data();
  static const std::regex re(R"(Version (\d+\.\d+(\.\d+)?))");
  std::smatch m;
  if (!std::regex_search(out, m, re)) throw SimError("'" + binary + " --version' printed no version: is SUMO installed?");
  return m[1].str();
}

void check_net_version(const std::filesystem::path& net_file, const std::string& net_version,
                       const std::string& sumo_version) {
  if (net_version.empty()) return;  // old nets carry no version; SUMO reads them
  const auto net = major_minor(net_version);
  const auto sumo = major_minor(sumo_version);
  if (net.first < 0) throw SimError("'" + net_file.string() + "' has an unreadable net version '" + net_version + "'");
  if (net > sumo) {
    throw SimError("'" + net_file.string() + "' was written by netconvert " + net_version + ", newer than the installed SUMO " +
                   sumo_version + ", which cannot read it reliably: rebuild the net with this SUMO's netconvert " +
                   "(netconvert -s NET -o NET) or install a newer SUMO");
  }
}

}  // namespace corridor::sim
