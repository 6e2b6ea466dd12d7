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

class SignalController {
 public:
  virtual ~SignalController() = default;
  // Moves to `phase` through safe transitions and holds it until released. Replaces a previous hold.
  virtual void hold(NodeId node, const maps::Phase& phase, double now_s) = 0;
  // Returns to the normal program through safe transitions, starting at program step `resume_step`.
  virtual void release(NodeId node, std::size_t resume_step, double now_s) = 0;
  [[nodiscard]] virtual SignalMode mode(NodeId node) const = 0;
  // Green still owed to the phase on show before it may end (for Trans).
  [[nodiscard]] virtual double remaining_min_green_s(NodeId node, double now_s) const = 0;
  // The plan phase on show, if what is shown is one.
  [[nodiscard]] virtual std::optional<std::size_t> current_phase(NodeId node) const = 0;
  // When `movement`'s current green began (t_G0), or nullopt while it is not green.
  [[nodiscard]] virtual std::optional<double> green_start_s(NodeId node, std::size_t movement) const = 0;
};

}  // namespace corridor::preemption
