// One intersection's NTCIP 1202 controller, simulated over a preemption::SignalController (the
// in-memory one running the map's programs, or SUMO's lights): what `corridor signal-agent` serves
// on each of its ports. It holds the objects Corridor sets and reads (oids.hpp) and runs a real
// preempt sequence: a call (preemptControlState.N = 1) starts entry (the running phase keeps its
// minimum green, then yellow and all-red), then dwell in the preempt's phase, until the call is
// removed; then exit back to the program. The controller owns the safe sequence; a call can only
// ask. Calls expire when not re-asserted (the watchdog) and after max presence, as field
// controllers' do. Phase control (hold, force-off, omit, vehicle call) gives priority without
// preemption: the called and held phases are served, the others forced off.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "maps/signal_plan.hpp"
#include "ntcip/oids.hpp"
#include "preemption/signal_controller.hpp"

namespace corridor::ntcip {

// A preempt input as the intersection is wired: the approach (and, where wired so, the one turning
// movement) it serves.
struct PreemptInput {
  std::uint32_t number = 1;
  maps::Compass approach = maps::Compass::north;
  std::optional<std::size_t> movement;  // plan movement index, where the input is for one movement
};

struct VirtualTiming {
  // A call not re-asserted for this long is dropped: a central system that went silent must not
  // keep the junction.
  double call_timeout_s = 30.0;
  // No preempt dwells longer than this (NTCIP's max presence); the call must be removed and placed
  // again to be served again.
  double max_presence_s = 180.0;
};

// A value of an object: INTEGER, OCTET STRING, OBJECT IDENTIFIER or TimeTicks.
struct Value {
  enum class Type : std::uint8_t { integer, octets, object_id, timeticks } type = Type::integer;
  std::int64_t integer = 0;
  std::string octets;
  Oid object_id;
};

enum class SetStatus : std::uint8_t { ok, no_such_object, not_writable, wrong_type, wrong_value };

class VirtualIntersection {
 public:
  // `controller` holds `node` with `plan`; both must outlive this. Throws std::invalid_argument for
  // preempt numbers that are not 1..n without gaps, or a movement not in the plan.
  VirtualIntersection(NodeId node, const maps::SignalPlan& plan, std::vector<PreemptInput> preempts,
                      preemption::SignalController& controller, std::string description, VirtualTiming timing = {});

  // The object, or nullopt where this controller has none.
  [[nodiscard]] std::optional<Value> get(const Oid& oid, double now_s) const;
  // The first object after `oid` in lexicographic order (GETNEXT), or nullopt past the last.
  [[nodiscard]] std::optional<Oid> next(const Oid& oid) const;
  // A SET is checked for all its objects first and applied only if all pass.
  [[nodiscard]] SetStatus check_set(const Oid& oid, const Value& value) const;
  void set(const Oid& oid, const Value& value, double now_s);
  // Moves the preempt and phase-control logic to now_s; call as time moves, before and after SETs.
  void step(double now_s);

  [[nodiscard]] PreemptState preempt_state(std::uint32_t number) const;
  [[nodiscard]] const std::vector<PreemptInput>& preempts() const { return preempts_; }
  // The preempt's phase: every movement of its approach that can be green together (its movement
  // first, where it is wired for one).
  [[nodiscard]] const maps::Phase& preempt_phase(std::uint32_t number) const;
  [[nodiscard]] NodeId node() const { return node_; }
  [[nodiscard]] std::size_t phase_count() const { return plan_.movements.size(); }  // NTCIP phase k+1 = movement k

 private:
  struct Call {
    bool on = false;
    double asserted_s = -1e18;  // last SET to 1
    double served_since_s = -1;  // when it became the active preempt; -1 when it is not
    bool locked_out = false;     // hit max presence: ignored until removed
  };
  enum class Serving : std::uint8_t { none, preempt, phase_control };

  [[nodiscard]] std::int32_t lights_bits(std::uint32_t group, preemption::Light light) const;
  [[nodiscard]] std::optional<std::uint32_t> active_preempt() const;
  [[nodiscard]] maps::Phase phase_control_phase() const;
  [[nodiscard]] std::size_t exit_step(const maps::Phase& held) const;
  void release(double now_s);

  NodeId node_;
  const maps::SignalPlan& plan_;
  std::vector<PreemptInput> preempts_;
  std::vector<maps::Phase> preempt_phases_;
  preemption::SignalController& controller_;
  std::string description_;
  VirtualTiming timing_;
  std::uint32_t groups_ = 1;
  std::vector<Oid> objects_;  // every OID served, sorted
  std::vector<Call> calls_;   // by preempt number - 1
  // Phase control, by group - 1.
  std::vector<std::int32_t> omit_, hold_, force_off_, veh_call_;
  Serving serving_ = Serving::none;
  std::optional<std::uint32_t> served_preempt_;  // the preempt being served, or exiting
  bool exiting_ = false;
  maps::Phase held_;
  double now_s_ = 0.0;
  double started_s_ = -1.0;  // the first step: sysUpTime counts from it
};

}  // namespace corridor::ntcip
