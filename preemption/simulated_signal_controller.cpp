#include "preemption/simulated_signal_controller.hpp"

#include <algorithm>
#include <limits>
#include <stdexcept>

namespace corridor::preemption {
namespace {

constexpr double kNever = std::numeric_limits<double>::infinity();

bool subset(const std::vector<std::uint8_t>& a, const std::vector<std::uint8_t>& b) {
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i] && !b[i]) return false;
  }
  return true;
}

}  // namespace

SimulatedSignalController::SimulatedSignalController(const std::unordered_map<NodeId, maps::SignalPlan>& plans,
                                                     double start_s) {
  for (const auto& [node, plan] : plans) {
    if (plan.program.empty()) continue;
    State s;
    s.plan = &plan;
    const maps::Phase& first = plan.phases[plan.program.front().phase];
    s.shown = first.green;
    s.lights.assign(plan.movements.size(), Light::red);
    for (std::size_t m = 0; m < s.shown.size(); ++m) {
      if (s.shown[m]) s.lights[m] = Light::green;
    }
    s.stage_start_s = s.green_since_s = s.step_green_start_s = start_s;
    s.green_start.assign(plan.movements.size(), start_s);
    s.min_green_s = first.min_green_s;
    s.shown_phase = plan.program.front().phase;
    states_.emplace(node, std::move(s));
  }
}

SimulatedSignalController::State& SimulatedSignalController::state(NodeId node) {
  auto it = states_.find(node);
  if (it == states_.end()) throw std::invalid_argument("no signal plan for node " + std::to_string(node.v));
  return it->second;
}

const SimulatedSignalController::State& SimulatedSignalController::state(NodeId node) const {
  auto it = states_.find(node);
  if (it == states_.end()) throw std::invalid_argument("no signal plan for node " + std::to_string(node.v));
  return it->second;
}

std::vector<std::uint8_t> SimulatedSignalController::desired(const State& s) const {
  if (s.mode == SignalMode::held) return s.held.green;
  return s.plan->phases[s.plan->program[s.step].phase].green;
}

double SimulatedSignalController::next_event_s(const State& s) const {
  switch (s.stage) {
    case Stage::yellow: return s.stage_start_s + s.plan->yellow_s;
    case Stage::all_red: return s.stage_start_s + s.plan->all_red_s;
    case Stage::green: break;
  }
  const auto want = desired(s);
  const bool program_phase_on = s.mode == SignalMode::program && s.shown == want;
  if (program_phase_on) {
    // The step runs its green, then the program moves on.
    return std::max(s.step_green_start_s + s.plan->program[s.step].green_s, s.green_since_s + s.min_green_s);
  }
  if (s.shown == want) return kNever;  // holding
  if (subset(s.shown, want)) return s.stage_start_s;  // only additions: at once
  return std::max(s.stage_start_s, s.green_since_s + s.min_green_s);
}

void SimulatedSignalController::step_state(NodeId node, State& s, double t) {
  const maps::SignalPlan& plan = *s.plan;
  const std::size_t n = plan.movements.size();
  switch (s.stage) {
    case Stage::yellow:
      for (std::size_t m = 0; m < n; ++m) {
        if (s.lights[m] == Light::yellow) s.lights[m] = Light::red;
      }
      s.stage = Stage::all_red;
      s.stage_start_s = t;
      emit(node, s, t);
      return;
    case Stage::all_red:
      s.stage = Stage::green;
      s.stage_start_s = t;
      break;  // fall through to showing what is wanted now
    case Stage::green:
      break;
  }
  auto want = desired(s);
  if (s.mode == SignalMode::program && s.shown == want && s.stage_start_s < t) {
    // The step's green is over: the program moves to its next step.
    s.step = (s.step + 1) % plan.program.size();
    want = desired(s);
  }
  if (!subset(s.shown, want)) {
    // Terminate what the next phase does not keep: yellow, then all-red.
    for (std::size_t m = 0; m < n; ++m) {
      if (s.shown[m] && !want[m]) {
        s.shown[m] = 0;
        s.lights[m] = Light::yellow;
      }
    }
    s.stage = Stage::yellow;
    s.stage_start_s = t;
    s.shown_phase.reset();
    emit(node, s, t);
    return;
  }
  // Everything on show may stay: add the rest. Conflicting movements were cleared above.
  bool added = false;
  for (std::size_t m = 0; m < n; ++m) {
    if (want[m] && !s.shown[m]) {
      s.shown[m] = 1;
      s.lights[m] = Light::green;
      s.green_start[m] = t;
      added = true;
    }
  }
  s.stage = Stage::green;
  s.stage_start_s = t;
  if (added || !s.shown_phase) {
    s.green_since_s = t;
    s.min_green_s = s.mode == SignalMode::held ? s.held.min_green_s : plan.phases[plan.program[s.step].phase].min_green_s;
  }
  if (s.mode == SignalMode::program) {
    s.shown_phase = plan.program[s.step].phase;
    s.step_green_start_s = t;
  } else {
    s.shown_phase.reset();
    for (std::size_t p = 0; p < plan.phases.size(); ++p) {
      if (plan.phases[p].green == s.shown) s.shown_phase = p;
    }
  }
  if (added) emit(node, s, t);
}

void SimulatedSignalController::emit(NodeId node, const State& s, double t) {
  if (observer_) observer_(node, s.lights, t);
}

void SimulatedSignalController::advance(double now_s) {
  for (auto& [node, s] : states_) {
    // Bounded: each event moves a stage forward; a cycle has a handful of events.
    for (int guard = 0; guard < 100000; ++guard) {
      const double t = next_event_s(s);
      if (t > now_s) break;
      step_state(node, s, t);
    }
  }
}

void SimulatedSignalController::hold(NodeId node, const maps::Phase& phase, double now_s) {
  State& s = state(node);
  if (phase.green.size() != s.plan->movements.size() || !s.plan->phase_is_safe(phase)) {
    throw std::invalid_argument("refusing to hold an unsafe or mismatched phase at node " + std::to_string(node.v));
  }
  advance(now_s);
  s.mode = SignalMode::held;
  s.held = phase;
  if (s.stage == Stage::green) s.stage_start_s = std::max(s.stage_start_s, now_s);
}

void SimulatedSignalController::release(NodeId node, std::size_t resume_step, double now_s) {
  State& s = state(node);
  advance(now_s);
  if (s.mode == SignalMode::program) return;
  s.mode = SignalMode::program;
  s.step = resume_step % s.plan->program.size();
  if (s.stage == Stage::green) s.stage_start_s = std::max(s.stage_start_s, now_s);
  // The resumed step's green starts when its phase is on show; it may already be.
  if (s.shown == desired(s)) s.step_green_start_s = now_s;
}

SignalMode SimulatedSignalController::mode(NodeId node) const { return state(node).mode; }

double SimulatedSignalController::remaining_min_green_s(NodeId node, double now_s) const {
  const State& s = state(node);
  return s.stage == Stage::green ? std::max(0.0, s.green_since_s + s.min_green_s - now_s) : 0.0;
}

std::optional<std::size_t> SimulatedSignalController::current_phase(NodeId node) const {
  const State& s = state(node);
  return s.stage == Stage::green ? s.shown_phase : std::nullopt;
}

std::optional<double> SimulatedSignalController::green_start_s(NodeId node, std::size_t movement) const {
  const State& s = state(node);
  if (movement >= s.lights.size() || s.lights[movement] != Light::green) return std::nullopt;
  return s.green_start[movement];
}

std::vector<ProgramInterval> SimulatedSignalController::program_forecast(NodeId node, double now_s, double horizon_s) const {
  const State& s = state(node);
  std::vector<ProgramInterval> out;
  if (s.mode != SignalMode::program) return out;
  const maps::SignalPlan& plan = *s.plan;
  const auto green_of = [&](std::size_t step) -> const std::vector<std::uint8_t>& { return plan.phases[plan.program[step].phase].green; };
  const auto both = [](const std::vector<std::uint8_t>& a, const std::vector<std::uint8_t>& b) {
    std::vector<std::uint8_t> c(a.size(), 0);
    for (std::size_t m = 0; m < a.size(); ++m) c[m] = a[m] && b[m];
    return c;
  };
  std::size_t step = s.step;
  double t = now_s;  // where the next interval starts
  if (s.stage == Stage::green && s.shown == desired(s)) {
    const double end = std::max(s.step_green_start_s + plan.program[step].green_s, s.green_since_s + s.min_green_s);
    out.push_back({now_s, std::max(end, now_s), s.shown, false, s.green_since_s + s.min_green_s});
    t = out.back().end_s;
  } else if (s.stage != Stage::green) {
    // A program clearance: yellow (what is left of it), then all-red, towards the step's phase.
    const double end = s.stage == Stage::yellow ? s.stage_start_s + plan.yellow_s + plan.all_red_s : s.stage_start_s + plan.all_red_s;
    out.push_back({now_s, std::max(end, now_s), both(s.shown, green_of(step)), true, 0.0});
    t = out.back().end_s;
    const maps::Phase& phase = plan.phases[plan.program[step].phase];
    out.push_back({t, t + std::max(plan.program[step].green_s, phase.min_green_s), phase.green, false, t + phase.min_green_s});
    t = out.back().end_s;
  } else {
    return out;  // green, but not the step's own phase: on its way back from a hold
  }
  // Bounded: a cycle per pass, and a horizon of minutes.
  for (int guard = 0; t < now_s + horizon_s && guard < 1000; ++guard) {
    const std::size_t next = (step + 1) % plan.program.size();
    const auto& from = green_of(step);
    const auto& to = green_of(next);
    if (!subset(from, to)) {
      out.push_back({t, t + plan.yellow_s + plan.all_red_s, both(from, to), true, 0.0});
      t = out.back().end_s;
    }
    const maps::Phase& phase = plan.phases[plan.program[next].phase];
    out.push_back({t, t + std::max(plan.program[next].green_s, phase.min_green_s), phase.green, false, t + phase.min_green_s});
    t = out.back().end_s;
    step = next;
  }
  return out;
}

HoldStage SimulatedSignalController::hold_stage(NodeId node) const {
  const State& s = state(node);
  if (s.mode == SignalMode::held) return s.stage == Stage::green && s.shown == s.held.green ? HoldStage::holding : HoldStage::entering;
  // Released, and not yet back on a program phase: on the way back.
  return s.stage == Stage::green && s.shown == desired(s) ? HoldStage::none : HoldStage::exiting;
}

const std::vector<Light>& SimulatedSignalController::lights(NodeId node) const { return state(node).lights; }

bool SimulatedSignalController::running_program(NodeId node) const {
  const State& s = state(node);
  return s.mode == SignalMode::program && s.stage == Stage::green && s.shown == desired(s);
}

std::size_t SimulatedSignalController::program_step(NodeId node) const { return state(node).step; }

}  // namespace corridor::preemption
