// The dispatch service's signal side: what each signal shows a console (its state, lights and
// mode), the preemption engine's events turned into stored rows and stream events, and detector
// counts for the queue estimate. Each takes preemption_mutex_, or runs under it (signal_state_locked,
// announce_signal_state, drain_preemption_events).
#include "server/dispatch_service.hpp"

#include <cmath>

#include "preemption/queue_estimator.hpp"

namespace corridor::server {

std::string DispatchService::signal_state_locked(NodeId node) const {
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
  return signals_.lights(node);
}

std::pair<std::string, std::size_t> DispatchService::signal_mode(NodeId node) const {
  if (signals_map_.signals.count(node) == 0) throw not_found("no signal at node " + std::to_string(node.v));
  std::lock_guard lock(preemption_mutex_);
  const char* mode = signals_.mode(node) == preemption::SignalMode::held ? "held"
                     : signals_.running_program(node)                    ? "program"
                                                                         : "clearing";
  return {mode, signals_.program_step(node)};
}

}  // namespace corridor::server
