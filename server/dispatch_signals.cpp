// The dispatch service's signal side: what each signal shows a console (its state, lights and
// mode), the preemption engine's events turned into stored rows and stream events, and detector
// counts for the queue estimate. Each takes preemption_mutex_, or runs under it (signal_state_locked,
// announce_signal_state, drain_preemption_events).
#include "server/dispatch_service.hpp"

#include <cmath>

#include "preemption/queue_estimator.hpp"
#include "server/dispatch_mission.hpp"

#include <algorithm>
#include <shared_mutex>

namespace corridor::server {

std::string DispatchService::signal_state_locked(NodeId node) const {
  if (routed_.in_field(node)) {
    // What the field controller reports of its preempt.
    switch (field_->hold_stage(node)) {
      case preemption::HoldStage::entering:
      case preemption::HoldStage::holding: return "held";
      case preemption::HoldStage::exiting: return "recovering";
      case preemption::HoldStage::none: break;
    }
    return preemption_.planned(node) ? "scheduled" : "normal";
  }
  if (signals_.mode(node) == preemption::SignalMode::held) return "held";
  // The program passes through yellow and all-red between its own steps too; it is recovering
  // only on its way back from a hold, until its own phase is on show again.
  if (!signals_.running_program(node)) {
    auto it = shown_signal_state_.find(node);
    if (it != shown_signal_state_.end() && (it->second == "held" || it->second == "recovering")) return "recovering";
  }
  if (preemption_.planned(node)) return "scheduled";
  return "normal";
}

std::string DispatchService::signal_name(NodeId signal) const {
  const auto it = signals_map_.names.find(signal);
  return it == signals_map_.names.end() ? std::string{} : it->second;
}

std::string DispatchService::signal_state(NodeId node) const {
  if (signals_map_.signals.count(node) == 0) throw not_found("no signal at node " + std::to_string(node.v));
  std::lock_guard lock(preemption_mutex_);
  return signal_state_locked(node);
}

void DispatchService::announce_signal_state(NodeId node, double now_s) {
  if (signals_map_.signals.count(node) == 0) return;
  std::string state = signal_state_locked(node);
  auto [it, fresh] = shown_signal_state_.try_emplace(node, "normal");
  if (it->second == state) return;
  it->second = state;
  DispatchEvent e;
  e.kind = "signal_state";
  e.signal = node;
  e.state = std::move(state);
  e.time_s = now_s;
  emit(std::move(e));
}

void DispatchService::announce_field_states(double now_s) {
  if (!field_) return;
  for (const ntcip::FieldStatus& f : field_->status()) {
    DispatchEvent e;
    e.kind = "signal_field";
    e.signal = f.signal;
    e.link = ntcip::to_string(f.link);
    e.preempt_state = f.preempt_state ? ntcip::to_string(*f.preempt_state) : "";
    e.call_on = f.call_on;
    e.reason = f.last_error;
    std::string key = e.link + '|' + e.preempt_state + '|' + (f.call_on ? '1' : '0');
    auto [it, fresh] = shown_field_state_.try_emplace(f.signal);
    if (!fresh && it->second == key) continue;
    it->second = std::move(key);
    e.time_s = now_s;
    emit(std::move(e));
  }
}

void DispatchService::drain_preemption_events(Staged& staged) {
  std::vector<std::pair<NodeId, double>> touched;
  for (const auto& e : preemption_.take_events()) {
    stage(staged, [e](Store& store) { store.insert_preemption_event(e); });
    DispatchEvent out;
    out.kind = "preemption_" + e.kind;
    out.mission = e.mission;
    out.reason = e.detail;
    out.time_s = e.time_s;
    out.signal = e.node;
    emit(std::move(out));
    touched.emplace_back(e.node, e.time_s);
  }
  // The signals these events touched may have changed state; the tick looks at all of them.
  for (const auto& [node, time_s] : touched) announce_signal_state(node, time_s);
}

void DispatchService::report_detectors(NodeId stop_line, const CountsReport& report, double now_s) {
  // Any node the signal controls names it: a detector sits on one stop line's approach.
  if (plans_.count(stop_line) == 0) throw not_found("no signal at node " + std::to_string(stop_line.v));
  const NodeId node = signals_map_.key(stop_line);
  std::lock_guard lock(preemption_mutex_);
  try {
    // Each part is checked before any is recorded, so that a report is taken whole or not at all.
    if (report.occupancy && !(*report.occupancy >= 0.0 && *report.occupancy <= 1.0)) {
      throw preemption::CountError("occupancy must be within [0, 1]");
    }
    if (report.speed_ratio && !(*report.speed_ratio >= 0.0 && std::isfinite(*report.speed_ratio))) {
      throw preemption::CountError("speed_ratio must be a finite number >= 0");
    }
    if (report.queue_m && !(*report.queue_m >= 0.0 && *report.queue_m <= 100000.0)) {
      throw preemption::CountError("queue_m must be a length in metres within [0, 100000]");
    }
    if (report.arrivals) preemption_.record_counts(node, report.approach, now_s, *report.arrivals, *report.departures);
    if (report.occupancy || report.speed_ratio) {
      preemption_.record_measurement(node, report.approach, report.occupancy, report.speed_ratio);
    }
    if (report.queue_m) preemption_.record_queue_length(node, report.approach, *report.queue_m);
  } catch (const preemption::CountError& e) {
    throw bad_request(e.what());
  }
}

std::vector<preemption::Light> DispatchService::signal_lights(NodeId node) const {
  if (signals_map_.signals.count(node) == 0) throw not_found("no signal at node " + std::to_string(node.v));
  std::lock_guard lock(preemption_mutex_);
  // A field controller's own report where its phases are wired; the in-memory program otherwise.
  if (routed_.in_field(node)) {
    auto lights = field_->lights_shown(node);
    if (!lights.empty()) return lights;
  }
  return signals_.lights(node);
}

std::optional<ntcip::FieldStatus> DispatchService::field_status(NodeId signal) const {
  if (!field_) return std::nullopt;
  return field_->status(signal);
}

void DispatchService::drain_call_records(Staged& staged) {
  if (!field_) return;
  for (const ntcip::CallRecord& c : field_->take_records()) {
    SignalCallRow row;
    row.id = c.id;
    row.signal = c.signal;
    row.controller = c.controller;
    row.missions.assign(c.missions.begin(), c.missions.end());
    if (!c.missions.empty()) {
      row.mission = c.missions.front();
      std::shared_lock registry(registry_mutex_);
      if (const auto it = missions_.find(c.missions.front()); it != missions_.end()) row.vehicle_id = it->second->row.vehicle_id;
    }
    row.priority = c.priority;
    row.kind = c.kind;
    row.preempt = c.preempt;
    row.approach = c.approach;
    row.request_s = c.request_s;
    row.grant_s = c.grant_s;
    row.release_s = c.release_s;
    row.clear_s = c.clear_s;
    row.outcome = c.outcome;
    stage(staged, [row](Store& store) { store.upsert_signal_call(row); });
    // The latest state of each record, for a server without a store.
    const auto same = std::find_if(recent_calls_.begin(), recent_calls_.end(), [&](const SignalCallRow& r) { return r.id == row.id; });
    if (same != recent_calls_.end()) {
      *same = row;
    } else {
      recent_calls_.push_front(row);
      if (recent_calls_.size() > 2000) recent_calls_.pop_back();
    }
    DispatchEvent e;
    e.kind = "signal_call";
    e.mission = row.mission.value_or(0);
    e.signal = row.signal;
    e.vehicle_id = row.vehicle_id;
    e.state = row.outcome;
    e.reason = row.kind + (row.kind == "preempt" ? " " + std::to_string(row.preempt) : std::string{}) + " approach=" + row.approach;
    e.time_s = row.clear_s.value_or(row.release_s.value_or(row.grant_s.value_or(row.request_s)));
    emit(std::move(e));
  }
}

std::vector<SignalCallRow> DispatchService::signal_calls(NodeId signal, std::size_t limit) {
  if (signals_map_.signals.count(signal) == 0) throw not_found("no signal at node " + std::to_string(signal.v));
  if (store_ != nullptr) {
    flush();  // what has been announced is also what is read
    return store_->signal_calls(signal, std::nullopt, limit);
  }
  std::lock_guard lock(preemption_mutex_);
  std::vector<SignalCallRow> out;
  for (const auto& r : recent_calls_) {
    if (r.signal == signal && out.size() < limit) out.push_back(r);
  }
  return out;
}

std::vector<SignalCallRow> DispatchService::mission_calls(MissionId mission, std::size_t limit) {
  (void)this->mission(mission);  // 404 for an unknown mission
  if (store_ != nullptr) {
    flush();
    return store_->signal_calls(std::nullopt, mission, limit);
  }
  std::lock_guard lock(preemption_mutex_);
  std::vector<SignalCallRow> out;
  for (const auto& r : recent_calls_) {
    if (std::find(r.missions.begin(), r.missions.end(), mission) != r.missions.end() && out.size() < limit) out.push_back(r);
  }
  return out;
}

std::pair<std::string, std::size_t> DispatchService::signal_mode(NodeId node) const {
  if (signals_map_.signals.count(node) == 0) throw not_found("no signal at node " + std::to_string(node.v));
  std::lock_guard lock(preemption_mutex_);
  if (routed_.in_field(node)) return {field_->mode(node) == preemption::SignalMode::held ? "held" : "program", 0};
  const char* mode = signals_.mode(node) == preemption::SignalMode::held ? "held"
                     : signals_.running_program(node)                    ? "program"
                                                                         : "clearing";
  return {mode, signals_.program_step(node)};
}

}  // namespace corridor::server
