#include "sim/sumo_signal_controller.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <fmt/format.h>

#include "sim/errors.hpp"

namespace corridor::sim {
namespace {

bool is_green(char c) { return c == 'G' || c == 'g'; }
bool is_yellow(char c) { return c == 'y' || c == 'Y'; }
bool has_green(const std::string& state) { return state.find_first_of("Gg") != std::string::npos; }
bool has_yellow(const std::string& state) { return state.find_first_of("yY") != std::string::npos; }

// Every yellow link turned red; `any` tells whether there was one.
std::string yellow_to_red(std::string state, bool& any) {
  any = false;
  for (char& c : state) {
    if (is_yellow(c)) {
      c = 'r';
      any = true;
    }
  }
  return state;
}

// Every green link that `keep` does not show green turned yellow.
std::string end_greens(std::string state, const std::string& keep, bool& any) {
  any = false;
  for (std::size_t i = 0; i < state.size(); ++i) {
    if (is_green(state[i]) && !is_green(keep[i])) {
      state[i] = 'y';
      any = true;
    }
  }
  return state;
}

std::string phase_state(const maps::Phase& phase) {
  std::string s(phase.green.size(), 'r');
  for (std::size_t i = 0; i < phase.green.size(); ++i) {
    if (phase.green[i] != 0) s[i] = 'G';
  }
  return s;
}

}  // namespace

SumoSignalController::SumoSignalController(const std::unordered_map<NodeId, maps::SignalPlan>& plans,
                                           const std::unordered_map<NodeId, const maps::SumoSignalPlan*>& sumo,
                                           const std::unordered_map<std::string, std::vector<maps::SumoTlPhase>>& sumo_phases,
                                           TrafficLightApi& api, const std::set<std::string>& actuated)
    : api_(api) {
  for (const auto& [node, plan] : plans) {
    const auto s = sumo.find(node);
    if (s == sumo.end()) throw SimError("no SUMO traffic light for the plan of node " + std::to_string(node.v));
    Light l;
    l.node = node;
    l.plan = &plan;
    l.tls = s->second->tls_id;
    l.program_id = s->second->program_id;
    const auto phases = sumo_phases.find(l.tls);
    if (phases == sumo_phases.end() || phases->second.empty()) throw SimError("traffic light '" + l.tls + "' has no phases");
    l.sumo_phases = phases->second;
    l.actuated = actuated.contains(l.tls);
    const std::size_t n = plan.movements.size();
    l.allowed_together.assign(n * n, 0);
    for (const auto& p : l.sumo_phases) {
      if (p.state.size() != n) throw SimError("traffic light '" + l.tls + "': program and plan differ in links");
      for (std::size_t a = 0; a < n; ++a) {
        for (std::size_t b = 0; b < n; ++b) {
          if (is_green(p.state[a]) && is_green(p.state[b])) l.allowed_together[a * n + b] = 1;
        }
      }
    }
    l.since_s.assign(n, -1e9);
    lights_.emplace(node, std::move(l));
  }
}

SumoSignalController::Light& SumoSignalController::light(NodeId node) {
  const auto it = lights_.find(node);
  if (it == lights_.end()) throw std::out_of_range("no SUMO traffic light at node " + std::to_string(node.v));
  return it->second;
}

const SumoSignalController::Light& SumoSignalController::light(NodeId node) const {
  const auto it = lights_.find(node);
  if (it == lights_.end()) throw std::out_of_range("no SUMO traffic light at node " + std::to_string(node.v));
  return it->second;
}

int SumoSignalController::sumo_phase_of_step(const Light& l, std::size_t step) const {
  std::size_t k = 0;
  for (std::size_t i = 0; i < l.sumo_phases.size(); ++i) {
    const auto& s = l.sumo_phases[i].state;
    if (!has_green(s) || has_yellow(s)) continue;
    if (k++ == step) return static_cast<int>(i);
  }
  return 0;
}

double SumoSignalController::program_min_green_left_s(Light& l) const {
  const int p = api_.phase(l.tls);
  if (p < 0 || static_cast<std::size_t>(p) >= l.sumo_phases.size()) return 0.0;
  const auto& ph = l.sumo_phases[static_cast<std::size_t>(p)];
  if (!has_green(ph.state) || has_yellow(ph.state)) return 0.0;
  const double min_green = ph.min_duration_s > 0 ? std::min(ph.min_duration_s, ph.duration_s) : std::min(5.0, ph.duration_s);
  return std::max(0.0, min_green - api_.spent_s(l.tls));
}

void SumoSignalController::show(Light& l, const std::string& state, double now_s) {
  const std::size_t n = state.size();
  const std::string before = l.shown.empty() ? api_.state(l.tls) : l.shown;
  const auto fail = [&](const std::string& what) {
    violations_.push_back(fmt::format("t={:.1f} tls {}: {} ({} -> {})", now_s, l.tls, what, before, state));
  };
  for (std::size_t i = 0; i < n; ++i) {
    const char was = i < before.size() ? before[i] : 'r';
    const char now = state[i];
    if (is_green(was) && now == 'r') fail(fmt::format("link {} went from green to red without yellow", i));
    if (is_yellow(was) && now == 'r' && now_s - l.since_s[i] < l.plan->yellow_s - 1e-6) {
      fail(fmt::format("link {} yellow for {:.1f} s, less than {:.1f} s", i, now_s - l.since_s[i], l.plan->yellow_s));
    }
    if (!is_green(was) && is_green(now)) {
      for (std::size_t j = 0; j < n; ++j) {
        if (j == i || !l.plan->conflicts(i, j) || l.allowed_together[i * n + j] != 0) continue;
        if (state[j] != 'r') fail(fmt::format("link {} turned green while conflicting link {} is not red", i, j));
        else if (now_s - l.since_s[j] < l.plan->all_red_s - 1e-6 && j < before.size() && before[j] == 'r' &&
                 l.since_s[j] > -1e8) {
          fail(fmt::format("link {} turned green {:.1f} s after conflicting link {} went red (all-red {:.1f} s)", i,
                           now_s - l.since_s[j], j, l.plan->all_red_s));
        }
      }
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    const char was = i < before.size() ? before[i] : 'r';
    const bool changed = (is_green(was) != is_green(state[i])) || (is_yellow(was) != is_yellow(state[i])) ||
                         ((was == 'r') != (state[i] == 'r'));
    if (changed) l.since_s[i] = now_s;
  }
  api_.set_state(l.tls, state);
  l.shown = state;
}

void SumoSignalController::hold(NodeId node, const maps::Phase& phase, double now_s) {
  Light& l = light(node);
  now_s_ = now_s;
  if (phase.green.size() != l.plan->movements.size()) throw std::invalid_argument("hold: phase does not fit the plan");
  const std::string target = phase_state(phase);
  if (l.stage == Stage::held && l.target == target && !l.release_pending) return;
  l.held_phase = phase;
  l.target = target;
  l.release_pending = false;
  if (l.stage == Stage::program) {
    l.taken_over = true;
    l.shown = api_.state(l.tls);
    // What SUMO showed: a link that was green is taken as green since now at the latest.
    for (std::size_t i = 0; i < l.shown.size(); ++i) l.since_s[i] = std::min(l.since_s[i], now_s);
    l.wait_until_s = now_s + program_min_green_left_s(l);
    l.stage = Stage::clear_yellow;
    l.stage_start_s = now_s;
    update(now_s);
    return;
  }
  // All-red still running before the held green was shown: only the target changes; the held
  // stage clears whatever the new target drops once the all-red has run.
  if (l.stage == Stage::held && l.held_since_s < 0.0) return;
  if (l.stage == Stage::held || l.stage == Stage::back_yellow || l.stage == Stage::back_all_red) {
    // Change of held phase: clear whatever is green and not in the new phase.
    l.wait_until_s = l.stage == Stage::held ? l.held_since_s + l.held_phase.min_green_s : now_s;
    l.stage = Stage::clear_yellow;
    l.stage_start_s = now_s;
    update(now_s);
  }
  // Already clearing towards a hold: the new target takes effect when the clearance ends.
}

void SumoSignalController::begin_return(Light& l, double now_s) {
  l.stage = Stage::back_yellow;
  l.stage_start_s = now_s;
  l.wait_until_s = l.held_since_s + l.held_phase.min_green_s;
  update(now_s);
}

void SumoSignalController::restore_program(Light& l, double now_s) {
  // getProgram answers "online" after setRedYellowGreenState: restore the id saved from the net,
  // then restart at a defined phase.
  api_.set_program(l.tls, l.program_id);
  api_.set_phase(l.tls, l.resume_sumo_phase);
  l.stage = Stage::program;
  l.shown.clear();
  l.release_pending = false;
  ++programs_restored_;
  spdlog::debug("event=signal_restored tls={} t={:.1f} phase={}", l.tls, now_s, l.resume_sumo_phase);
}

void SumoSignalController::release(NodeId node, std::size_t resume_step, double now_s) {
  Light& l = light(node);
  now_s_ = now_s;
  if (l.stage == Stage::program) return;
  l.resume_sumo_phase = sumo_phase_of_step(l, resume_step % std::max<std::size_t>(1, l.plan->program.size()));
  l.release_pending = true;
  if (l.stage == Stage::held) begin_return(l, now_s);
  // While clearing towards a hold, the clearance finishes first, then the light goes back.
}

void SumoSignalController::update(double now_s) {
  now_s_ = now_s;
  for (auto& [node, l] : lights_) {
    // Loop: a stage may end at once (nothing to clear).
    for (int guard = 0; guard < 6; ++guard) {
      const Stage before = l.stage;
      if (l.stage == Stage::clear_yellow) {
        if (now_s < l.wait_until_s) break;
        bool any = false;
        std::string s = end_greens(l.shown, l.target, any);
        // A permissive green the held phase keeps becomes a protected one.
        for (std::size_t i = 0; i < s.size(); ++i) {
          if (s[i] == 'g') s[i] = 'G';
        }
        if (any) show(l, s, now_s);
        const bool yellow_left = l.shown.find_first_of("yY") != std::string::npos;
        l.stage = Stage::clear_all_red;
        l.stage_start_s = now_s;
        if (yellow_left) l.stage_start_s = now_s;  // yellow runs from here
        l.wait_until_s = yellow_left ? now_s + l.plan->yellow_s : now_s;
      } else if (l.stage == Stage::clear_all_red) {
        if (now_s < l.wait_until_s) break;
        bool any = false;
        const std::string s = yellow_to_red(l.shown, any);
        if (any) show(l, s, now_s);
        l.stage = Stage::held;
        l.wait_until_s = any ? now_s + l.plan->all_red_s : now_s;
        l.stage_start_s = now_s;
        l.held_since_s = -1.0;  // green not shown yet
      } else if (l.stage == Stage::held) {
        if (l.held_since_s < 0.0) {
          if (now_s < l.wait_until_s) break;
          if (l.release_pending) {
            restore_program(l, now_s);  // released before the held green was shown
            break;
          }
          // The target may have changed while the clearance ran: a link still green that the new
          // target drops is cleared (yellow, all-red) before anything turns green.
          bool drops = false;
          for (std::size_t i = 0; i < l.shown.size() && i < l.target.size(); ++i) {
            drops = drops || (is_green(l.shown[i]) && !is_green(l.target[i]));
          }
          if (drops) {
            l.stage = Stage::clear_yellow;
            l.stage_start_s = now_s;
            l.wait_until_s = now_s;
            continue;
          }
          show(l, l.target, now_s);
          l.held_since_s = now_s;
          ++holds_reached_;
        }
        break;
      } else if (l.stage == Stage::back_yellow) {
        if (now_s < l.wait_until_s) break;
        const std::string& resume = l.sumo_phases[static_cast<std::size_t>(l.resume_sumo_phase)].state;
        bool any = false;
        const std::string s = end_greens(l.shown, resume, any);
        if (any) show(l, s, now_s);
        l.stage = Stage::back_all_red;
        l.stage_start_s = now_s;
        l.wait_until_s = any ? now_s + l.plan->yellow_s : now_s;
      } else if (l.stage == Stage::back_all_red) {
        if (now_s < l.wait_until_s) break;
        bool any = false;
        const std::string s = yellow_to_red(l.shown, any);
        if (any) {
          show(l, s, now_s);
          l.wait_until_s = now_s + l.plan->all_red_s;
          l.stage_start_s = now_s;
          // Stay in back_all_red with nothing yellow: the next pass hands the light back.
          break;
        }
        restore_program(l, now_s);
        break;
      }
      if (l.stage == before) break;
    }
  }
}

preemption::SignalMode SumoSignalController::mode(NodeId node) const {
  return light(node).stage == Stage::program ? preemption::SignalMode::program : preemption::SignalMode::held;
}

double SumoSignalController::remaining_min_green_s(NodeId node, double now_s) const {
  const Light& l = light(node);
  if (l.stage == Stage::program) return program_min_green_left_s(const_cast<Light&>(l));
  if (l.stage == Stage::held && l.held_since_s >= 0.0) return std::max(0.0, l.held_since_s + l.held_phase.min_green_s - now_s);
  return 0.0;
}

std::optional<std::size_t> SumoSignalController::current_phase(NodeId node) const {
  const Light& l = light(node);
  if (l.stage == Stage::held && l.held_since_s >= 0.0) {
    for (std::size_t p = 0; p < l.plan->phases.size(); ++p) {
      if (l.plan->phases[p].green == l.held_phase.green) return p;
    }
    return std::nullopt;
  }
  if (l.stage != Stage::program) return std::nullopt;
  const int p = api_.phase(l.tls);
  if (p < 0 || static_cast<std::size_t>(p) >= l.sumo_phases.size()) return std::nullopt;
  const std::string& s = l.sumo_phases[static_cast<std::size_t>(p)].state;
  if (!has_green(s) || has_yellow(s)) return std::nullopt;
  std::vector<std::uint8_t> green(s.size(), 0);
  for (std::size_t i = 0; i < s.size(); ++i) green[i] = is_green(s[i]) ? 1 : 0;
  for (std::size_t k = 0; k < l.plan->phases.size(); ++k) {
    if (l.plan->phases[k].green == green) return k;
  }
  return std::nullopt;
}

std::optional<double> SumoSignalController::green_start_s(NodeId node, std::size_t movement) const {
  const Light& l = light(node);
  if (l.stage == Stage::held && l.held_since_s >= 0.0) {
    if (movement < l.held_phase.green.size() && l.held_phase.green[movement] != 0) return l.held_since_s;
    return std::nullopt;
  }
  if (l.stage != Stage::program) return std::nullopt;
  const std::string s = api_.state(l.tls);
  if (movement >= s.size() || !is_green(s[movement])) return std::nullopt;
  return now_s_ - api_.spent_s(l.tls);
}

std::vector<preemption::ProgramInterval> SumoSignalController::program_forecast(NodeId node, double now_s, double horizon_s) const {
  const Light& l = light(node);
  std::vector<preemption::ProgramInterval> out;
  if (l.stage != Stage::program) return out;
  const int p = api_.phase(l.tls);
  if (p < 0 || static_cast<std::size_t>(p) >= l.sumo_phases.size()) return out;
  const auto interval = [&](const maps::SumoTlPhase& ph, double start, double end) {
    preemption::ProgramInterval iv;
    iv.start_s = start;
    iv.end_s = end;
    iv.green.assign(ph.state.size(), 0);
    for (std::size_t i = 0; i < ph.state.size(); ++i) iv.green[i] = is_green(ph.state[i]) ? 1 : 0;
    iv.clearance = has_yellow(ph.state) || !has_green(ph.state);
    const double min_green = ph.min_duration_s > 0 ? std::min(ph.min_duration_s, ph.duration_s) : std::min(5.0, ph.duration_s);
    iv.min_green_end_s = start + min_green;
    return iv;
  };
  std::size_t k = static_cast<std::size_t>(p);
  const maps::SumoTlPhase& on_show = l.sumo_phases[k];
  const double spent = api_.spent_s(l.tls);
  if (l.actuated) {
    // SUMO may end it as soon as its minimum duration is served, and times what follows itself.
    const double min_end = now_s + std::max(0.0, (on_show.min_duration_s > 0 ? on_show.min_duration_s : on_show.duration_s) - spent);
    out.push_back(interval(on_show, now_s, min_end));
    out.back().min_green_end_s = min_end;
    return out;
  }
  double t = now_s + std::max(0.0, on_show.duration_s - spent);
  out.push_back(interval(on_show, now_s, t));
  out.back().min_green_end_s = now_s - spent + (out.back().min_green_end_s - now_s);
  // Bounded: a horizon of minutes and programs of a few dozen phases.
  for (int guard = 0; t < now_s + horizon_s && guard < 2000; ++guard) {
    k = (k + 1) % l.sumo_phases.size();
    const double d = std::max(l.sumo_phases[k].duration_s, 0.1);
    out.push_back(interval(l.sumo_phases[k], t, t + d));
    t += d;
  }
  return out;
}

preemption::HoldStage SumoSignalController::hold_stage(NodeId node) const {
  const Light& l = light(node);
  switch (l.stage) {
    case Stage::program: return preemption::HoldStage::none;
    case Stage::clear_yellow:
    case Stage::clear_all_red: return preemption::HoldStage::entering;
    case Stage::held:
      if (l.release_pending) return preemption::HoldStage::exiting;
      return l.held_since_s >= 0.0 ? preemption::HoldStage::holding : preemption::HoldStage::entering;
    case Stage::back_yellow:
    case Stage::back_all_red: return preemption::HoldStage::exiting;
  }
  return preemption::HoldStage::none;
}

std::vector<preemption::Light> SumoSignalController::lights_shown(NodeId node) const {
  const Light& l = light(node);
  const std::string state = l.stage == Stage::program ? api_.state(l.tls) : l.shown;
  std::vector<preemption::Light> out(state.size(), preemption::Light::red);
  for (std::size_t i = 0; i < state.size(); ++i) {
    out[i] = is_green(state[i]) ? preemption::Light::green : is_yellow(state[i]) ? preemption::Light::yellow : preemption::Light::red;
  }
  return out;
}

std::size_t SumoSignalController::lights_taken_over() const {
  return static_cast<std::size_t>(std::count_if(lights_.begin(), lights_.end(), [](const auto& kv) { return kv.second.taken_over; }));
}

std::size_t SumoSignalController::lights_on_program() const {
  return static_cast<std::size_t>(std::count_if(lights_.begin(), lights_.end(), [](const auto& kv) {
    return kv.second.taken_over && kv.second.stage == Stage::program;
  }));
}

}  // namespace corridor::sim
