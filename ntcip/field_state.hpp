// One field controller's state inside FieldSignalController: its wiring, what Corridor wants of it,
// what was last asserted and answered, what it reports, and its link. Private to the
// FieldSignalController sources.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "ntcip/field_signals.hpp"

namespace corridor::ntcip {

struct FieldSignalController::Field {
  ControllerConfig config;
  NodeId signal;
  const maps::SignalPlan* plan = nullptr;
  SnmpManager::SessionId session = 0;
  std::uint32_t groups = 1;  // phase groups the wiring reaches
  // NTCIP phase number -> the plan movements it shows.
  std::map<std::uint32_t, std::vector<std::size_t>> phase_movements;

  // What Corridor wants.
  enum class Want : std::uint8_t { none, preempt, phase_control } want = Want::none;
  std::uint32_t want_preempt = 0;
  std::vector<std::uint32_t> want_phases;
  // What was last asserted and answered.
  std::uint32_t asserted_preempt = 0;  // 0: no call on (as far as the controller acknowledged)
  bool asserted_phase_control = false;
  double last_assert_s = -1e18;
  double last_poll_s = -1e18;
  bool in_flight = false;        // a request is outstanding: no second one piles up behind it
  double in_flight_since_s = 0.0;
  bool startup_checked = false;  // every wired call read once, and any on cleared

  // What the controller reports.
  std::map<std::uint32_t, PreemptState> preempt_states;
  std::map<std::uint32_t, bool> control_states;
  std::vector<preemption::Light> lights;
  std::vector<double> green_since;
  bool lights_known = false;

  // The link.
  int failures = 0;
  LinkState link = LinkState::unreachable;
  double next_try_s = 0.0;
  std::optional<double> last_answer_s;
  std::string last_error;

  std::optional<CallRecord> call;
  std::vector<double> rtt_ms;  // a ring of the last answers' round trips
  std::size_t answers = 0;
  bool unreachable_during_call = false;
  bool max_presence_seen = false;
};

}  // namespace corridor::ntcip
