// The NTCIP 1202 (v2) objects Corridor sets and reads on an actuated signal controller, under
// devices.asc (1.3.6.1.4.1.1206.4.2.1), and their values. Each table's index is the last
// sub-identifier: preempt number N, phase group G (phases 8G-7..8G, phase 8(G-1)+k in bit k-1).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace corridor::ntcip {

using Oid = std::vector<std::uint32_t>;

// The column's OID with the index appended.
[[nodiscard]] inline Oid column(const Oid& base, std::uint32_t index) {
  Oid out = base;
  out.push_back(index);
  return out;
}
[[nodiscard]] std::string to_string(const Oid& oid);  // "1.3.6.1..."

namespace oid {
inline const Oid kAsc{1, 3, 6, 1, 4, 1, 1206, 4, 2, 1};
// phase: maxPhases.0, maxPhaseGroups.0, the phase status and phase control group tables.
inline const Oid kMaxPhases{1, 3, 6, 1, 4, 1, 1206, 4, 2, 1, 1, 1, 0};
inline const Oid kMaxPhaseGroups{1, 3, 6, 1, 4, 1, 1206, 4, 2, 1, 1, 3, 0};
inline const Oid kPhaseStatusGroupReds{1, 3, 6, 1, 4, 1, 1206, 4, 2, 1, 1, 4, 1, 2};
inline const Oid kPhaseStatusGroupYellows{1, 3, 6, 1, 4, 1, 1206, 4, 2, 1, 1, 4, 1, 3};
inline const Oid kPhaseStatusGroupGreens{1, 3, 6, 1, 4, 1, 1206, 4, 2, 1, 1, 4, 1, 4};
inline const Oid kPhaseControlGroupPhaseOmit{1, 3, 6, 1, 4, 1, 1206, 4, 2, 1, 1, 5, 1, 2};
inline const Oid kPhaseControlGroupHold{1, 3, 6, 1, 4, 1, 1206, 4, 2, 1, 1, 5, 1, 4};
inline const Oid kPhaseControlGroupForceOff{1, 3, 6, 1, 4, 1, 1206, 4, 2, 1, 1, 5, 1, 5};
inline const Oid kPhaseControlGroupVehCall{1, 3, 6, 1, 4, 1, 1206, 4, 2, 1, 1, 5, 1, 6};
// preempt: maxPreempts.0, preemptState.N, preemptControlState.N.
inline const Oid kMaxPreempts{1, 3, 6, 1, 4, 1, 1206, 4, 2, 1, 6, 1, 0};
inline const Oid kPreemptState{1, 3, 6, 1, 4, 1, 1206, 4, 2, 1, 6, 2, 1, 16};
inline const Oid kPreemptControlState{1, 3, 6, 1, 4, 1, 1206, 4, 2, 1, 6, 3, 1, 2};
// MIB-II system group, so that generic SNMP tools can tell what answers.
inline const Oid kSysDescr{1, 3, 6, 1, 2, 1, 1, 1, 0};
inline const Oid kSysObjectId{1, 3, 6, 1, 2, 1, 1, 2, 0};
inline const Oid kSysUpTime{1, 3, 6, 1, 2, 1, 1, 3, 0};
}  // namespace oid

// preemptState's values.
enum class PreemptState : std::int32_t {
  other = 1,
  not_active = 2,
  not_active_with_call = 3,
  entry_started = 4,
  track_service = 5,
  dwell = 6,
  link_active = 7,
  exit_started = 8,
  max_presence = 9,
};
[[nodiscard]] const char* to_string(PreemptState s);  // "notActive", "dwell", ...
// In service: the controller has taken the call (entry, track, dwell, link).
[[nodiscard]] inline bool in_service(PreemptState s) {
  return s == PreemptState::entry_started || s == PreemptState::track_service || s == PreemptState::dwell ||
         s == PreemptState::link_active;
}

// The phases (1-based NTCIP phase numbers) of a group's bits, and the bits of a set of phases in group g.
[[nodiscard]] std::vector<std::uint32_t> phases_of_group(std::uint32_t group, std::int32_t bits);
[[nodiscard]] std::int32_t group_bits(std::uint32_t group, const std::vector<std::uint32_t>& phases);

}  // namespace corridor::ntcip
