#include "localizer/match/fcd_trace.hpp"

#include <expat.h>

#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>

#include "localizer/match/trace_io.hpp"

namespace corridor::localizer {
namespace {

struct FcdParser {
  std::map<std::string, std::vector<TruthSample>> vehicles;
  std::string prefix;
  double time_s = 0;
  bool in_timestep = false;
  bool saw_fcd = false;

  static const char* attr(const char** attrs, const char* key) {
    for (int i = 0; attrs[i] != nullptr; i += 2) {
      if (std::strcmp(attrs[i], key) == 0) return attrs[i + 1];
    }
    return nullptr;
  }

  void start(const char* name, const char** attrs) {
    if (std::strcmp(name, "fcd-export") == 0) saw_fcd = true;
    if (std::strcmp(name, "timestep") == 0) {
      const char* t = attr(attrs, "time");
      time_s = t != nullptr ? std::strtod(t, nullptr) : 0.0;
      in_timestep = true;
      return;
    }
    if (!in_timestep || std::strcmp(name, "vehicle") != 0) return;
    const char* id = attr(attrs, "id");
    const char* x = attr(attrs, "x");
    const char* y = attr(attrs, "y");
    if (id == nullptr || x == nullptr || y == nullptr) return;
    if (!prefix.empty() && std::strncmp(id, prefix.c_str(), prefix.size()) != 0) return;
    TruthSample s;
    s.time_s = time_s;
    s.position = {std::strtod(y, nullptr), std::strtod(x, nullptr)};
    if (const char* a = attr(attrs, "angle")) s.heading_deg = std::strtod(a, nullptr);
    if (const char* v = attr(attrs, "speed")) s.speed_mps = std::strtod(v, nullptr);
    if (const char* l = attr(attrs, "lane")) s.lane = l;
    if (maps::is_valid_lat_lon(s.position)) vehicles[id].push_back(s);
  }

  void end(const char* name) {
    if (std::strcmp(name, "timestep") == 0) in_timestep = false;
  }
};

}  // namespace

std::map<std::string, std::vector<TruthSample>> read_fcd(const std::filesystem::path& file, const std::string& prefix) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw TraceError("fcd file not found: '" + file.string() + "'");
  std::unique_ptr<XML_ParserStruct, decltype(&XML_ParserFree)> parser(XML_ParserCreate(nullptr), &XML_ParserFree);
  FcdParser fcd;
  fcd.prefix = prefix;
  XML_SetUserData(parser.get(), &fcd);
  XML_SetElementHandler(
      parser.get(), [](void* self, const char* name, const char** attrs) { static_cast<FcdParser*>(self)->start(name, attrs); },
      [](void* self, const char* name) { static_cast<FcdParser*>(self)->end(name); });
  std::vector<char> buffer(1 << 16);
  while (in) {
    in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    const auto got = static_cast<int>(in.gcount());
    if (XML_Parse(parser.get(), buffer.data(), got, got == 0 ? 1 : 0) == XML_STATUS_ERROR) {
      throw TraceError("'" + file.string() + "' is not well-formed XML: " + XML_ErrorString(XML_GetErrorCode(parser.get())));
    }
    if (got == 0) break;
  }
  XML_Parse(parser.get(), nullptr, 0, 1);
  if (!fcd.saw_fcd) throw TraceError("'" + file.string() + "' is not SUMO fcd output (no <fcd-export>)");
  return fcd.vehicles;
}

}  // namespace corridor::localizer
