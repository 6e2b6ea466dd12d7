#include "ntcip/field_signals.hpp"

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

void FieldSignalController::on_reply(Field& f, const SnmpReply& r, double now_s, double sent_s) {
  f.in_flight = false;
  if (r.outcome == SnmpReply::Outcome::ok || r.outcome == SnmpReply::Outcome::error_status) {
    constexpr std::size_t kRing = 4096;
    const double rtt = std::max(0.0, now_s - sent_s) * 1e3;
    if (f.rtt_ms.size() < kRing) {
      f.rtt_ms.push_back(rtt);
    } else {
      f.rtt_ms[f.answers % kRing] = rtt;
    }
    ++f.answers;
  }
  if (r.outcome == SnmpReply::Outcome::timeout || r.outcome == SnmpReply::Outcome::failure) {
    ++f.failures;
    const LinkState before = f.link;
    f.link = f.failures >= 3 ? LinkState::unreachable : LinkState::degraded;
    f.last_error = r.message;
    // Backoff: 1, 2, 4 ... 30 s between tries, so that a dead controller costs little.
    f.next_try_s = now_s + std::min(30.0, std::pow(2.0, std::min(f.failures - 1, 5)));
    if (f.link == LinkState::unreachable) f.unreachable_during_call = f.unreachable_during_call || f.call.has_value();
    if (before != f.link) {
      spdlog::warn("event=ntcip_link controller={} link={} failures={} error=\"{}\"", f.config.id, to_string(f.link), f.failures, r.message);
    }
    return;
  }
  if (f.link != LinkState::up) spdlog::info("event=ntcip_link controller={} link=up", f.config.id);
  f.failures = 0;
  f.next_try_s = now_s;
  f.last_answer_s = now_s;
  if (r.outcome == SnmpReply::Outcome::error_status) {
    f.link = LinkState::degraded;  // it answers, but refuses what was asked
    f.last_error = r.message;
    spdlog::warn("event=ntcip_error_status controller={} status={} index={} error=\"{}\"", f.config.id, r.error_status, r.error_index,
                 r.message);
    return;
  }
  f.link = LinkState::up;
  f.last_error.clear();
  for (const auto& [o, value] : r.values) {
    if (!value) continue;
    if (o.size() == oid::kPreemptState.size() + 1 && std::equal(oid::kPreemptState.begin(), oid::kPreemptState.end(), o.begin())) {
      f.preempt_states[o.back()] = static_cast<PreemptState>(*value);
    } else if (o.size() == oid::kPreemptControlState.size() + 1 &&
               std::equal(oid::kPreemptControlState.begin(), oid::kPreemptControlState.end(), o.begin())) {
      f.control_states[o.back()] = *value != 0;
    } else if (o.size() == oid::kPhaseStatusGroupGreens.size() + 1 &&
               std::equal(oid::kPhaseStatusGroupGreens.begin(), oid::kPhaseStatusGroupGreens.end(), o.begin())) {
      if (f.lights.empty()) f.lights.assign(f.plan->movements.size(), preemption::Light::red);
      for (std::uint32_t k = 0; k < 8; ++k) {
        const std::uint32_t phase = 8 * (o.back() - 1) + k + 1;
        const auto it = f.phase_movements.find(phase);
        if (it == f.phase_movements.end()) continue;
        const bool green = (*value & (1 << k)) != 0;
        for (std::size_t m : it->second) {
          if (green && f.lights[m] != preemption::Light::green) f.green_since[m] = now_s;
          if (green) {
            f.lights[m] = preemption::Light::green;
          } else if (f.lights[m] == preemption::Light::green) {
            f.lights[m] = preemption::Light::red;  // yellows, below, refine it
          }
        }
      }
      f.lights_known = !f.phase_movements.empty();
    } else if (o.size() == oid::kPhaseStatusGroupYellows.size() + 1 &&
               std::equal(oid::kPhaseStatusGroupYellows.begin(), oid::kPhaseStatusGroupYellows.end(), o.begin())) {
      if (f.lights.empty()) f.lights.assign(f.plan->movements.size(), preemption::Light::red);
      for (std::uint32_t k = 0; k < 8; ++k) {
        const auto it = f.phase_movements.find(8 * (o.back() - 1) + k + 1);
        if (it == f.phase_movements.end() || (*value & (1 << k)) == 0) continue;
        for (std::size_t m : it->second) f.lights[m] = preemption::Light::yellow;
      }
    }
  }
  update_call(f, now_s);
}

void FieldSignalController::tick(double now_s) {
  std::lock_guard lock(mutex_);
  for (auto& [key, fp] : fields_) {
    Field& f = *fp;
    // A request the library never answered (it always should: an answer or a timeout) is given up
    // well after its last try, so that the controller is not stuck.
    if (f.in_flight && now_s - f.in_flight_since_s > f.config.timeout_s * (f.config.retries + 1) + 5.0) {
      spdlog::warn("event=ntcip_request_lost controller={}", f.config.id);
      on_reply(f, SnmpReply{SnmpReply::Outcome::timeout, 0, 0, "no answer (request lost)", {}}, now_s, now_s);
    }
    if (f.in_flight || now_s < f.next_try_s) continue;
    f.in_flight_since_s = now_s;
    const double sent = clock_();
    const auto done = [this, &f, sent](const SnmpReply& r) {
      std::lock_guard l(mutex_);
      on_reply(f, r, clock_(), sent);
    };
    if (!f.startup_checked) {
      // Any call a previous run left on (it was killed mid-hold) is cleared before anything else.
      std::vector<Oid> read;
      for (const PreemptWiring& p : f.config.preempts) read.push_back(column(oid::kPreemptControlState, p.number));
      f.in_flight = true;
      snmp_->get(f.session, read, [this, &f, sent](const SnmpReply& r) {
        std::lock_guard l(mutex_);
        const double now = clock_();
        on_reply(f, r, now, sent);
        if (!r.ok()) return;
        std::vector<std::pair<Oid, std::int64_t>> off;
        for (const auto& [o, v] : r.values) {
          if (v && *v != 0 && f.want != Field::Want::preempt) off.emplace_back(o, 0);
        }
        f.startup_checked = true;
        if (off.empty()) return;
        for (const auto& [o, v] : off) {
          CallRecord c;
          c.id = std::max(last_record_id_ + 1, static_cast<std::uint64_t>(now * 1e6));
          last_record_id_ = c.id;
          c.signal = f.signal;
          c.controller = f.config.id;
          c.kind = "preempt";
          c.preempt = o.back();
          c.request_s = c.release_s.emplace(now);
          c.clear_s = now;
          c.outcome = "orphan_cleared";
          changed_.push_back(c);
          spdlog::warn("event=ntcip_orphan_cleared controller={} preempt={} detail=\"a call left on by an earlier run\"", f.config.id,
                       o.back());
        }
        f.in_flight = true;
        f.in_flight_since_s = now;
        snmp_->set(f.session, std::move(off), [this, &f, now](const SnmpReply& reply) {
          std::lock_guard l2(mutex_);
          on_reply(f, reply, clock_(), now);
        });
      });
      continue;
    }
    // Calls, removals and keep-alive, in one SET.
    std::vector<std::pair<Oid, std::int64_t>> writes;
    const bool preempt_changed = (f.want == Field::Want::preempt ? f.want_preempt : 0) != f.asserted_preempt;
    const bool keepalive_due = now_s - f.last_assert_s >= f.config.keepalive_s;
    if (preempt_changed || (f.want == Field::Want::preempt && keepalive_due)) {
      if (f.asserted_preempt != 0 && f.asserted_preempt != f.want_preempt) writes.emplace_back(column(oid::kPreemptControlState, f.asserted_preempt), 0);
      if (f.want == Field::Want::preempt) writes.emplace_back(column(oid::kPreemptControlState, f.want_preempt), 1);
    }
    const bool control_wanted = f.want == Field::Want::phase_control;
    if (control_wanted != f.asserted_phase_control || (control_wanted && keepalive_due)) {
      for (std::uint32_t g = 1; g <= f.groups; ++g) {
        const std::int32_t bits = control_wanted ? group_bits(g, f.want_phases) : 0;
        writes.emplace_back(column(oid::kPhaseControlGroupHold, g), bits);
        writes.emplace_back(column(oid::kPhaseControlGroupVehCall, g), bits);
        writes.emplace_back(column(oid::kPhaseControlGroupForceOff, g), control_wanted ? (~bits & 0xFF) : 0);
      }
    }
    if (!writes.empty()) {
      f.in_flight = true;
      f.last_assert_s = now_s;
      const std::uint32_t asserted = f.want == Field::Want::preempt ? f.want_preempt : 0;
      snmp_->set(f.session, std::move(writes), [this, &f, asserted, control_wanted, sent](const SnmpReply& r) {
        std::lock_guard l(mutex_);
        if (r.ok()) {
          f.asserted_preempt = asserted;
          f.asserted_phase_control = control_wanted;
        } else if (r.outcome == SnmpReply::Outcome::error_status && f.call && !f.call->grant_s) {
          // Refused (not writable, wrong value): this call cannot be served here.
          f.call->outcome = "denied";
        }
        on_reply(f, r, clock_(), sent);
      });
      continue;
    }
    if (now_s - f.last_poll_s < f.config.poll_s) continue;
    std::vector<Oid> read;
    for (const PreemptWiring& p : f.config.preempts) {
      read.push_back(column(oid::kPreemptState, p.number));
      read.push_back(column(oid::kPreemptControlState, p.number));
    }
    if (!f.phase_movements.empty()) {
      for (std::uint32_t g = 1; g <= f.groups; ++g) {
        read.push_back(column(oid::kPhaseStatusGroupGreens, g));
        read.push_back(column(oid::kPhaseStatusGroupYellows, g));
      }
    }
    if (read.empty()) continue;
    f.in_flight = true;
    f.last_poll_s = now_s;
    snmp_->get(f.session, std::move(read), done);
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
