// An in-memory traffic signal controller for every planned intersection: runs each normal program,
// obeys hold/release, and sequences every change through min green, yellow and all-red. Used by
// tests and by the server when no simulator is attached. Time only moves through advance().
#pragma once

#include <functional>
#include <unordered_map>

#include "preemption/signal_controller.hpp"

namespace corridor::preemption {

class SimulatedSignalController final : public SignalController {
 public:
  using LightObserver = std::function<void(NodeId, const std::vector<Light>&, double time_s)>;

  // Every plan starts at program step 0, green since `start_s`. Plans must outlive the controller.
  SimulatedSignalController(const std::unordered_map<NodeId, maps::SignalPlan>& plans, double start_s);

  // Called with every change of an intersection's lights, at the exact time it happens.
  void set_observer(LightObserver observer) { observer_ = std::move(observer); }

  // Runs every intersection's timers up to now_s. Commands take effect from their own time.
  void advance(double now_s);

  void hold(NodeId node, const maps::Phase& phase, double now_s) override;
  void release(NodeId node, std::size_t resume_step, double now_s) override;
  [[nodiscard]] SignalMode mode(NodeId node) const override;
  [[nodiscard]] double remaining_min_green_s(NodeId node, double now_s) const override;
  [[nodiscard]] std::optional<std::size_t> current_phase(NodeId node) const override;
  [[nodiscard]] std::optional<double> green_start_s(NodeId node, std::size_t movement) const override;
  // Exact for the program it runs, from a program phase on show or a program clearance.
  [[nodiscard]] std::vector<ProgramInterval> program_forecast(NodeId node, double now_s, double horizon_s) const override;
  [[nodiscard]] HoldStage hold_stage(NodeId node) const override;
  [[nodiscard]] std::vector<Light> lights_shown(NodeId node) const override { return lights(node); }

  [[nodiscard]] const std::vector<Light>& lights(NodeId node) const;
  // True while nothing is being cleared and the program's own phase is on show.
  [[nodiscard]] bool running_program(NodeId node) const;
  [[nodiscard]] std::size_t program_step(NodeId node) const;

 private:
  enum class Stage { green, yellow, all_red };
  struct State {
    const maps::SignalPlan* plan;
    std::vector<Light> lights;
    std::vector<std::uint8_t> shown;  // movements green now
    std::vector<double> green_start;  // per movement, when its current green began
    Stage stage = Stage::green;
    double stage_start_s = 0;  // when the current stage began
    double green_since_s = 0;  // when the phase on show got its green (min green counts from here)
    double min_green_s = 0;
    std::optional<std::size_t> shown_phase;
    SignalMode mode = SignalMode::program;
    maps::Phase held;  // valid in held mode
    std::size_t step = 0;
    double step_green_start_s = 0;  // when the program step's phase began its green
  };

  State& state(NodeId node);
  const State& state(NodeId node) const;
  [[nodiscard]] std::vector<std::uint8_t> desired(const State& s) const;
  // Next moment something must change at this intersection, or +inf.
  [[nodiscard]] double next_event_s(const State& s) const;
  void step_state(NodeId node, State& s, double t);
  void emit(NodeId node, const State& s, double t);

  std::unordered_map<NodeId, State> states_;
  LightObserver observer_;
};

}  // namespace corridor::preemption
