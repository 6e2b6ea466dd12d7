#include "ntcip/oids.hpp"

namespace corridor::ntcip {

std::string to_string(const Oid& oid) {
  std::string out;
  for (std::uint32_t v : oid) out += (out.empty() ? "" : ".") + std::to_string(v);
  return out;
}

const char* to_string(PreemptState s) {
  switch (s) {
    case PreemptState::other: return "other";
    case PreemptState::not_active: return "notActive";
    case PreemptState::not_active_with_call: return "notActiveWithCall";
    case PreemptState::entry_started: return "entryStarted";
    case PreemptState::track_service: return "trackService";
    case PreemptState::dwell: return "dwell";
    case PreemptState::link_active: return "linkActive";
    case PreemptState::exit_started: return "exitStarted";
    case PreemptState::max_presence: return "maxPresence";
  }
  return "other";
}

std::vector<std::uint32_t> phases_of_group(std::uint32_t group, std::int32_t bits) {
  std::vector<std::uint32_t> out;
  for (std::uint32_t k = 0; k < 8; ++k) {
    if ((static_cast<std::uint32_t>(bits) & (1u << k)) != 0) out.push_back(8 * (group - 1) + k + 1);
  }
  return out;
}

std::int32_t group_bits(std::uint32_t group, const std::vector<std::uint32_t>& phases) {
  std::uint32_t bits = 0;
  for (std::uint32_t p : phases) {
    if (p >= 8 * (group - 1) + 1 && p <= 8 * group) bits |= 1u << (p - 8 * (group - 1) - 1);
  }
  return static_cast<std::int32_t>(bits);
}

}  // namespace corridor::ntcip
