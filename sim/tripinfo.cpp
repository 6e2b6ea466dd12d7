#include "sim/tripinfo.hpp"

#include <expat.h>

#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>

#include "sim/errors.hpp"

namespace corridor::sim {
namespace {

double number(const char** attrs, const char* key, double fallback) {
  for (int i = 0; attrs[i] != nullptr; i += 2) {
    if (std::strcmp(attrs[i], key) == 0) return std::strtod(attrs[i + 1], nullptr);
  }
  return fallback;
}

std::string text(const char** attrs, const char* key) {
  for (int i = 0; attrs[i] != nullptr; i += 2) {
    if (std::strcmp(attrs[i], key) == 0) return attrs[i + 1];
  }
  return {};
}

void XMLCALL on_start(void* data, const char* name, const char** attrs) {
  if (std::strcmp(name, "tripinfo") != 0) return;
  auto* out = static_cast<std::vector<TripInfo>*>(data);
  TripInfo t;
  t.id = text(attrs, "id");
  t.vtype = text(attrs, "vType");
  t.depart_s = number(attrs, "depart", 0.0);
  t.arrival_s = number(attrs, "arrival", -1.0);
  t.duration_s = number(attrs, "duration", 0.0);
  t.time_loss_s = number(attrs, "timeLoss", 0.0);
  t.waiting_time_s = number(attrs, "waitingTime", 0.0);
  t.waiting_count = static_cast<int>(number(attrs, "waitingCount", 0.0));
  out->push_back(std::move(t));
}

}  // namespace

std::vector<TripInfo> read_tripinfo(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw SimError("cannot read the tripinfo file " + file.string());
  std::vector<TripInfo> trips;
  std::unique_ptr<XML_ParserStruct, decltype(&XML_ParserFree)> parser(XML_ParserCreate(nullptr), &XML_ParserFree);
  XML_SetUserData(parser.get(), &trips);
  XML_SetStartElementHandler(parser.get(), on_start);
  char buffer[1 << 16];
  while (true) {
    in.read(buffer, sizeof buffer);
    const auto got = static_cast<int>(in.gcount());
    const bool last = got < static_cast<int>(sizeof buffer);
    if (XML_Parse(parser.get(), buffer, got, last) == XML_STATUS_ERROR) {
      throw SimError(file.string() + ":" + std::to_string(XML_GetCurrentLineNumber(parser.get())) +
                     ": malformed tripinfo XML: " + XML_ErrorString(XML_GetErrorCode(parser.get())));
    }
    if (last) break;
  }
  return trips;
}

}  // namespace corridor::sim
