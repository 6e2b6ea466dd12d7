// libFuzzer target for controllers files (corridor serve --controllers FILE) and the manifests
// corridor signal-agent writes, which are the same format: any input either parses into
// controllers that write back and read again to the same, or is refused with ControllersFileError
// (or JSON's own error, which the file reader reports as not JSON). Any other exception, a crash or a sanitizer report is a finding.
#include <nlohmann/json.hpp>

#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "ntcip/controllers_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace corridor::ntcip;
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception&) {  // what read_controllers_file reports as "not JSON"
    return 0;
  }
  try {
    const auto controllers = parse_controllers(j);
    const nlohmann::json written = to_json(controllers);
    const auto again = parse_controllers(written);  // what was accepted must read back
    if (again.size() != controllers.size() || to_json(again) != written) std::abort();
  } catch (const ControllersFileError&) {
    // A clear refusal, naming the field, is the expected outcome for bad input.
  } catch (...) {
    std::abort();
  }
  return 0;
}
