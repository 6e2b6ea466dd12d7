#include "ntcip/field_signals.hpp"
#include "ntcip/field_state.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <thread>

namespace corridor::ntcip {

const char* to_string(LinkState s) {
  switch (s) {
    case LinkState::up: return "up";
    case LinkState::degraded: return "degraded";
    case LinkState::unreachable: return "unreachable";
  }
  return "unreachable";
}

namespace {

std::optional<NodeId> signal_of(const maps::RoadGraph& graph, const maps::SignalMap& signals, const ControllerConfig& c) {
  for (const auto& [key, plan] : signals.signals) {
    if (c.tls_id) {
      const auto name = signals.names.find(key);
      if (name != signals.names.end() && name->second == *c.tls_id) return key;
    } else if (signals.names.empty() && graph.osm_node(key).v == *c.osm_node_id) {
      return key;
    }
  }
  return std::nullopt;
}

std::string where(const ControllerConfig& c) { return "controller '" + c.id + "'"; }

}  // namespace

FieldSignalController::FieldSignalController(const maps::RoadGraph& graph, const maps::SignalMap& signals,
                                             std::vector<ControllerConfig> controllers, Clock clock)
    : clock_(std::move(clock)) {
  for (ControllerConfig& c : controllers) {
    const auto key = signal_of(graph, signals, c);
    if (!key) {
      throw ControllersFileError(where(c) + ": " +
                                 (c.tls_id ? "the map has no traffic light '" + *c.tls_id + "'"
                                           : "the map has no signalized intersection at OSM node " + std::to_string(*c.osm_node_id)));
    }
    auto f = std::make_unique<Field>();
    f->signal = *key;
    f->plan = &signals.signals.at(*key);
    const maps::SignalPlan& plan = *f->plan;
    const auto has_approach = [&](maps::Compass side) {
      return std::any_of(plan.movements.begin(), plan.movements.end(), [&](const maps::Movement& m) { return m.from == side; });
    };
    for (const PreemptWiring& p : c.preempts) {
      if (!has_approach(p.approach)) {
        throw ControllersFileError(where(c) + ": preempt " + std::to_string(p.number) + " is wired to approach " +
                                   to_string(p.approach) + ", which the intersection does not have");
      }
    }
    for (const PhaseControlWiring& p : c.phase_control) {
      if (!has_approach(p.approach)) {
        throw ControllersFileError(where(c) + ": phase control is wired to approach " + std::string(to_string(p.approach)) +
                                   ", which the intersection does not have");
      }
      for (std::uint32_t ph : p.phases) f->groups = std::max(f->groups, (ph + 7) / 8);
    }
    for (const PhaseWiring& p : c.phases) {
      std::vector<std::size_t> movements;
      for (std::size_t m = 0; m < plan.movements.size(); ++m) {
        if (plan.movements[m].label() == p.movement) movements.push_back(m);
      }
      if (movements.empty()) {
        throw ControllersFileError(where(c) + ": phase " + std::to_string(p.number) + " is wired to movement " + p.movement +
                                   ", which the intersection does not have");
      }
      f->phase_movements[p.number] = std::move(movements);
      f->groups = std::max(f->groups, (p.number + 7) / 8);
    }
    f->green_since.assign(plan.movements.size(), 0.0);
    f->config = std::move(c);
    if (fields_.contains(*key)) throw ControllersFileError(where(f->config) + ": its intersection has another controller");
    fields_.emplace(*key, std::move(f));
  }
  if (fields_.empty()) return;
  snmp_ = std::make_unique<SnmpManager>();
  for (auto& [key, f] : fields_) {
    f->session = snmp_->open({f->config.host, f->config.port, f->config.snmp, f->config.timeout_s, f->config.retries});
  }
}

FieldSignalController::~FieldSignalController() {
  if (!snmp_) return;
  // Shutdown: no call is left on behind us.
  std::size_t waiting = 0;
  std::mutex done_mutex;
  std::size_t done = 0;
  {
    std::lock_guard lock(mutex_);
    for (auto& [key, f] : fields_) {
      std::vector<std::pair<Oid, std::int64_t>> off;
      for (const PreemptWiring& p : f->config.preempts) {
        if (f->asserted_preempt == p.number || f->want == Field::Want::preempt) off.emplace_back(column(oid::kPreemptControlState, p.number), 0);
      }
      if (f->asserted_phase_control || f->want == Field::Want::phase_control) {
        for (std::uint32_t g = 1; g <= f->groups; ++g) {
          for (const Oid& col : {oid::kPhaseControlGroupHold, oid::kPhaseControlGroupForceOff, oid::kPhaseControlGroupVehCall}) {
            off.emplace_back(column(col, g), 0);
          }
        }
      }
      if (off.empty()) continue;
      ++waiting;
      spdlog::info("event=ntcip_shutdown_clear controller={}", f->config.id);
      snmp_->set(f->session, std::move(off), [&done_mutex, &done](const SnmpReply&) {
        std::lock_guard l(done_mutex);
        ++done;
      });
    }
  }
  for (int i = 0; i < 200; ++i) {
    {
      std::lock_guard l(done_mutex);
      if (done >= waiting) break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  snmp_.reset();  // joins the SNMP thread before the fields go
}

std::vector<NodeId> FieldSignalController::signals() const {
  std::vector<NodeId> out;
  for (const auto& [key, f] : fields_) out.push_back(key);
  return out;
}

FieldSignalController::Field& FieldSignalController::field(NodeId node) {
  const auto it = fields_.find(node);
  if (it == fields_.end()) throw std::out_of_range("no field controller at node " + std::to_string(node.v));
  return *it->second;
}

const FieldSignalController::Field& FieldSignalController::field(NodeId node) const {
  const auto it = fields_.find(node);
  if (it == fields_.end()) throw std::out_of_range("no field controller at node " + std::to_string(node.v));
  return *it->second;
}

void FieldSignalController::touch(Field& f) {
  if (f.call) changed_.push_back(*f.call);
}

void FieldSignalController::hold(NodeId node, const maps::Phase& phase, double now_s) {
  hold_for(node, phase, preemption::HoldRequest{}, now_s);
}

void FieldSignalController::hold_for(NodeId node, const maps::Phase& phase, const preemption::HoldRequest& request, double now_s) {
  std::lock_guard lock(mutex_);
  Field& f = field(node);
  const maps::SignalPlan& plan = *f.plan;
  // The vehicle's approach, from its movement (else from the phase's first movement).
  std::optional<std::size_t> movement = request.movements.empty() ? std::nullopt : std::optional(request.movements.front());
  for (std::size_t m = 0; m < phase.green.size() && !movement; ++m) {
    if (phase.green[m]) movement = m;
  }
  if (!movement || *movement >= plan.movements.size()) return;
  const maps::Movement& mv = plan.movements[*movement];
  const std::string label = mv.label();
  const bool by_preempt = f.config.mode == PriorityMode::preempt ||
                          (f.config.mode == PriorityMode::by_priority &&
                           (request.priority >= f.config.preempt_min_priority || f.config.phase_control.empty()));
  Field::Want want = Field::Want::none;
  std::uint32_t preempt = 0;
  std::vector<std::uint32_t> phases;
  const auto pick_preempt = [&] {
    for (const PreemptWiring& p : f.config.preempts) {
      if (p.movement && *p.movement == label) return p.number;
    }
    for (const PreemptWiring& p : f.config.preempts) {
      if (!p.movement && p.approach == mv.from) return p.number;
    }
    return std::uint32_t{0};
  };
  const auto pick_phases = [&] {
    for (const PhaseControlWiring& p : f.config.phase_control) {
      if (p.movement && *p.movement == label) return p.phases;
    }
    for (const PhaseControlWiring& p : f.config.phase_control) {
      if (!p.movement && p.approach == mv.from) return p.phases;
    }
    return std::vector<std::uint32_t>{};
  };
  if (by_preempt && (preempt = pick_preempt()) != 0) {
    want = Field::Want::preempt;
  } else if (!(phases = pick_phases()).empty()) {
    want = Field::Want::phase_control;
  } else if ((preempt = pick_preempt()) != 0) {
    want = Field::Want::preempt;
  }
  if (want == Field::Want::none) {
    spdlog::warn("event=ntcip_no_wiring controller={} movement={} detail=\"no preempt or phase control wired for it\"", f.config.id,
                 label);
    return;
  }
  const bool same = want == f.want && preempt == f.want_preempt && phases == f.want_phases;
  f.want = want;
  f.want_preempt = preempt;
  f.want_phases = phases;
  if (same && f.call) {
    if (f.call->missions != request.missions) {
      f.call->missions = request.missions;
      f.call->priority = request.priority;
      touch(f);
    }
    return;
  }
  // A new call (or another input): the old record is released, a new one opens.
  if (f.call && !f.call->release_s) {
    f.call->release_s = now_s;
    touch(f);
  }
  CallRecord r;
  r.id = std::max(last_record_id_ + 1, static_cast<std::uint64_t>(clock_() * 1e6));
  last_record_id_ = r.id;
  r.signal = f.signal;
  r.controller = f.config.id;
  r.missions = request.missions;
  r.priority = request.priority;
  r.kind = want == Field::Want::preempt ? "preempt" : "phase_control";
  r.preempt = preempt;
  r.approach = to_string(mv.from);
  r.request_s = now_s;
  f.call = r;
  f.unreachable_during_call = f.link == LinkState::unreachable;
  f.max_presence_seen = false;
  f.last_assert_s = -1e18;  // asserted at the next tick, at once
  spdlog::info("event=ntcip_call_requested controller={} kind={} preempt={} approach={} missions={}", f.config.id, r.kind, preempt,
               r.approach, request.missions.size());
  touch(f);
}

void FieldSignalController::release(NodeId node, std::size_t /*resume_step*/, double now_s) {
  std::lock_guard lock(mutex_);
  Field& f = field(node);
  // The field controller exits its preempt by its own rules; Corridor only removes the call.
  f.want = Field::Want::none;
  f.want_preempt = 0;
  f.want_phases.clear();
  f.last_assert_s = -1e18;
  if (f.call && !f.call->release_s) {
    f.call->release_s = now_s;
    spdlog::info("event=ntcip_call_released controller={} preempt={}", f.config.id, f.call->preempt);
    touch(f);
  }
}

void FieldSignalController::update_call(Field& f, double now_s) {
  if (!f.call) return;
  CallRecord& c = *f.call;
  const bool known = c.kind == "preempt" && f.preempt_states.contains(c.preempt);
  const PreemptState state = known ? f.preempt_states.at(c.preempt) : PreemptState::other;
  if (known && state == PreemptState::max_presence) f.max_presence_seen = true;
  if (!c.grant_s) {
    const bool granted = c.kind == "preempt" ? known && in_service(state)
                                             : f.lights_known && std::any_of(f.phase_movements.begin(), f.phase_movements.end(), [&](const auto& kv) {
                                                 return std::find(f.want_phases.begin(), f.want_phases.end(), kv.first) != f.want_phases.end() &&
                                                        std::any_of(kv.second.begin(), kv.second.end(), [&](std::size_t m) {
                                                          return f.lights[m] == preemption::Light::green;
                                                        });
                                               });
    if (granted && !c.release_s) {
      c.grant_s = now_s;
      spdlog::info("event=ntcip_call_granted controller={} preempt={} after_s={:.1f}", f.config.id, c.preempt, now_s - c.request_s);
      touch(f);
    }
  }
  // Cleared: released, the controller has the call off, and its preempt is out of service.
  if (c.release_s && f.asserted_preempt == 0 && !f.asserted_phase_control) {
    const bool out = c.kind != "preempt" || !known || (!in_service(state) && state != PreemptState::exit_started);
    if (out) {
      c.clear_s = now_s;
      c.outcome = c.grant_s ? "served" : f.max_presence_seen ? "timed_out" : f.unreachable_during_call ? "unreachable" : "denied";
      if (c.grant_s && f.max_presence_seen) c.outcome = "timed_out";
      spdlog::info("event=ntcip_call_cleared controller={} preempt={} outcome={}", f.config.id, c.preempt, c.outcome);
      touch(f);
      f.call.reset();
    }
  }
}

std::vector<CallRecord> FieldSignalController::take_records() {
  std::lock_guard lock(mutex_);
  std::vector<CallRecord> out;
  out.swap(changed_);
  return out;
}

std::optional<FieldStatus> FieldSignalController::status(NodeId signal) const {
  std::lock_guard lock(mutex_);
  const auto it = fields_.find(signal);
  if (it == fields_.end()) return std::nullopt;
  const Field& f = *it->second;
  FieldStatus s;
  s.signal = f.signal;
  s.controller = f.config.id;
  s.link = f.link;
  s.last_error = f.last_error;
  s.last_answer_s = f.last_answer_s;
  s.call_on = f.want != Field::Want::none;
  s.preempt = f.call && f.call->kind == "preempt" ? f.call->preempt : f.want_preempt;
  if (s.preempt != 0 && f.preempt_states.contains(s.preempt)) s.preempt_state = f.preempt_states.at(s.preempt);
  if (f.lights_known) s.lights = f.lights;
  s.answers = f.answers;
  if (!f.rtt_ms.empty()) {
    std::vector<double> sorted = f.rtt_ms;
    std::sort(sorted.begin(), sorted.end());
    const auto at = [&](double q) { return sorted[std::min(sorted.size() - 1, static_cast<std::size_t>(q * static_cast<double>(sorted.size())))]; };
    s.rtt_p50_ms = at(0.5);
    s.rtt_p99_ms = at(0.99);
  }
  return s;
}

std::vector<FieldStatus> FieldSignalController::status() const {
  std::vector<FieldStatus> out;
  for (const NodeId n : signals()) out.push_back(*status(n));
  return out;
}

preemption::SignalMode FieldSignalController::mode(NodeId node) const {
  std::lock_guard lock(mutex_);
  return field(node).want != Field::Want::none ? preemption::SignalMode::held : preemption::SignalMode::program;
}

double FieldSignalController::remaining_min_green_s(NodeId node, double /*now_s*/) const {
  std::lock_guard lock(mutex_);
  const Field& f = field(node);
  double worst = 0.0;
  for (const maps::Phase& p : f.plan->phases) worst = std::max(worst, p.min_green_s);
  return worst;
}

std::optional<std::size_t> FieldSignalController::current_phase(NodeId node) const {
  std::lock_guard lock(mutex_);
  const Field& f = field(node);
  if (!f.lights_known) return std::nullopt;
  std::vector<std::uint8_t> green(f.lights.size(), 0);
  for (std::size_t m = 0; m < f.lights.size(); ++m) green[m] = f.lights[m] == preemption::Light::green ? 1 : 0;
  for (std::size_t p = 0; p < f.plan->phases.size(); ++p) {
    if (f.plan->phases[p].green == green) return p;
  }
  return std::nullopt;
}

std::optional<double> FieldSignalController::green_start_s(NodeId node, std::size_t movement) const {
  std::lock_guard lock(mutex_);
  const Field& f = field(node);
  if (!f.lights_known || movement >= f.lights.size() || f.lights[movement] != preemption::Light::green) return std::nullopt;
  return f.green_since[movement];
}

preemption::HoldStage FieldSignalController::hold_stage(NodeId node) const {
  std::lock_guard lock(mutex_);
  const Field& f = field(node);
  const std::uint32_t n = f.call && f.call->kind == "preempt" ? f.call->preempt : 0;
  if (n == 0 || !f.preempt_states.contains(n)) return f.want != Field::Want::none ? preemption::HoldStage::entering : preemption::HoldStage::none;
  switch (f.preempt_states.at(n)) {
    case PreemptState::entry_started:
    case PreemptState::track_service: return preemption::HoldStage::entering;
    case PreemptState::dwell:
    case PreemptState::link_active: return preemption::HoldStage::holding;
    case PreemptState::exit_started: return preemption::HoldStage::exiting;
    default: return f.want != Field::Want::none ? preemption::HoldStage::entering : preemption::HoldStage::none;
  }
}

std::vector<preemption::Light> FieldSignalController::lights_shown(NodeId node) const {
  std::lock_guard lock(mutex_);
  const Field& f = field(node);
  return f.lights_known ? f.lights : std::vector<preemption::Light>{};
}

}  // namespace corridor::ntcip
