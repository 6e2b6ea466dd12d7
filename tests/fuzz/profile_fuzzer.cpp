// libFuzzer target for vehicle profiles read from JSON (corridor route --profile FILE): any input
// either loads a profile that passes validation or throws ProfileError. Any other exception, a
// crash or a sanitizer report is a finding. Build with the `fuzz` preset and run scripts/fuzz.sh.
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "planner/vehicle_profile.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace corridor::planner;
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    const VehicleProfile p = profile_from_json(text);
    validate(p);  // what was accepted must be valid
    (void)profile_from_json(profile_to_json(p));  // and must read back
  } catch (const ProfileError&) {
    // A clear refusal is the expected outcome for bad input.
  } catch (...) {
    std::abort();
  }
  return 0;
}
