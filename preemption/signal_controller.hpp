// The commands preemption gives a traffic signal. Implemented in memory here (SimulatedSignal-
// Controller) and for SUMO in sim/. Implementations own the safe sequencing: min green, yellow and
// all-red are theirs to honour, whatever the caller asks and when.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "maps/ids.hpp"
#include "maps/signal_plan.hpp"

namespace corridor::preemption {

enum class Light : std::uint8_t { red, yellow, green };

enum class SignalMode : std::uint8_t {
  program,  // running the normal program
  held,     // preempted: moving to or holding a phase for an emergency vehicle
};

// Where a hold stands, as a field controller reports its preempt: clearing towards the held phase
// (entry), its green on show (dwell), or clearing back to the normal program (exit).
enum class HoldStage : std::uint8_t { none, entering, holding, exiting };

// A stretch of time over which the normal program shows one set of greens, as the controller
// foresees it: a phase's green, or the clearance between two phases (whose greens are then the
// movements green on both sides of it).
struct ProgramInterval {
  double start_s = 0.0;
  double end_s = 0.0;
  std::vector<std::uint8_t> green;  // per movement, 1 = green throughout
  bool clearance = false;           // yellow and all-red between two phases
  double min_green_end_s = 0.0;     // a phase: when its minimum green is served
};

// Who a hold is for: the movements the vehicles make and the missions whose claims it serves (the
// highest priority first), so that a field controller can pick the preempt input wired to the
// vehicle's approach, or priority without preemption, and keep a record of each call.
struct HoldRequest {
  std::vector<std::size_t> movements;
  std::vector<std::uint64_t> missions;
  int priority = 0;  // the highest of theirs
};

class SignalController {
 public:
  virtual ~SignalController() = default;
  // Moves to `phase` through safe transitions and holds it until released. Replaces a previous hold.
  virtual void hold(NodeId node, const maps::Phase& phase, double now_s) = 0;
  // The same, saying whom the hold is for; a controller with no use for it just holds.
  virtual void hold_for(NodeId node, const maps::Phase& phase, const HoldRequest& /*request*/, double now_s) {
    hold(node, phase, now_s);
  }
  // Returns to the normal program through safe transitions, starting at program step `resume_step`.
  virtual void release(NodeId node, std::size_t resume_step, double now_s) = 0;
  [[nodiscard]] virtual SignalMode mode(NodeId node) const = 0;
  // Green still owed to the phase on show before it may end (for Trans).
  [[nodiscard]] virtual double remaining_min_green_s(NodeId node, double now_s) const = 0;
  // The plan phase on show, if what is shown is one.
  [[nodiscard]] virtual std::optional<std::size_t> current_phase(NodeId node) const = 0;
  // When `movement`'s current green began (t_G0), or nullopt while it is not green.
  [[nodiscard]] virtual std::optional<double> green_start_s(NodeId node, std::size_t movement) const = 0;
  // What the normal program will show from now_s on, interval by interval, for at least horizon_s
  // where the controller can tell (a fixed program), less where it cannot (an actuated phase's
  // length), and nothing while it holds or clears for a hold: the engine then times a start from
  // what is on show now alone.
  [[nodiscard]] virtual std::vector<ProgramInterval> program_forecast(NodeId /*node*/, double /*now_s*/,
                                                                      double /*horizon_s*/) const {
    return {};
  }
  // Where the hold stands; controllers that cannot tell answer from mode() alone.
  [[nodiscard]] virtual HoldStage hold_stage(NodeId node) const {
    return mode(node) == SignalMode::held ? HoldStage::holding : HoldStage::none;
  }
  // What each movement shows now; empty where the controller cannot tell.
  [[nodiscard]] virtual std::vector<Light> lights_shown(NodeId /*node*/) const { return {}; }
};

}  // namespace corridor::preemption
