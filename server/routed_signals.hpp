// One SignalController over two: the field controllers' (NTCIP) for the signals they control, the
// in-memory one for the rest, so that the preemption engine drives both alike.
#pragma once

#include "ntcip/field_signals.hpp"
#include "preemption/simulated_signal_controller.hpp"

namespace corridor::server {

class RoutedSignals final : public preemption::SignalController {
 public:
  RoutedSignals(preemption::SimulatedSignalController& memory, ntcip::FieldSignalController* field) : memory_(memory), field_(field) {}

  void hold(NodeId node, const maps::Phase& phase, double now_s) override { to(node).hold(node, phase, now_s); }
  void hold_for(NodeId node, const maps::Phase& phase, const preemption::HoldRequest& request, double now_s) override {
    to(node).hold_for(node, phase, request, now_s);
  }
  void release(NodeId node, std::size_t resume_step, double now_s) override { to(node).release(node, resume_step, now_s); }
  [[nodiscard]] preemption::SignalMode mode(NodeId node) const override { return to(node).mode(node); }
  [[nodiscard]] double remaining_min_green_s(NodeId node, double now_s) const override {
    return to(node).remaining_min_green_s(node, now_s);
  }
  [[nodiscard]] std::optional<std::size_t> current_phase(NodeId node) const override { return to(node).current_phase(node); }
  [[nodiscard]] std::optional<double> green_start_s(NodeId node, std::size_t movement) const override {
    return to(node).green_start_s(node, movement);
  }
  [[nodiscard]] std::vector<preemption::ProgramInterval> program_forecast(NodeId node, double now_s, double horizon_s) const override {
    return to(node).program_forecast(node, now_s, horizon_s);
  }
  [[nodiscard]] preemption::HoldStage hold_stage(NodeId node) const override { return to(node).hold_stage(node); }
  [[nodiscard]] std::vector<preemption::Light> lights_shown(NodeId node) const override { return to(node).lights_shown(node); }

  [[nodiscard]] bool in_field(NodeId node) const { return field_ != nullptr && field_->controls(node); }

 private:
  [[nodiscard]] preemption::SignalController& to(NodeId node) const {
    if (in_field(node)) return *field_;
    return memory_;
  }
  preemption::SimulatedSignalController& memory_;
  ntcip::FieldSignalController* field_;
};

}  // namespace corridor::server
