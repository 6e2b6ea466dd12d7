// FieldSignalController's link to its controllers: each one's answers (round trips, link state,
// backoff, what it reports) and, every tick, the requests it is due: the startup check that clears
// orphaned calls, calls, removals and keep-alives in one SET, and the state poll.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>

#include "ntcip/field_signals.hpp"
#include "ntcip/field_state.hpp"

namespace corridor::ntcip {

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

}  // namespace corridor::ntcip
