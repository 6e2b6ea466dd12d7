// The signals a server drives in the field over NTCIP 1202: a preemption::SignalController for the
// intersections of a controllers file. A hold is a preempt call on the input wired to the vehicle's
// approach (preemptControlState.N = 1), or, for a lower priority or where the agency wires it so,
// priority by phase control (hold and vehicle call for the vehicle's phases, force-off for the
// others); the controller owns the safe sequence. A held call is re-asserted while wanted and
// always cleared: on release, on shutdown, and at start for any call a previous run left behind.
// The controllers' state (preemptState, what they show) is read as they answer; one that does not
// is retried with backoff and reported, and delays no other intersection and never the caller.
// Every call is recorded as field systems keep them: request, grant, release, clear and outcome.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "maps/road_graph.hpp"
#include "maps/signal_map.hpp"
#include "ntcip/controllers_file.hpp"
#include "ntcip/oids.hpp"
#include "ntcip/snmp_manager.hpp"
#include "preemption/signal_controller.hpp"

namespace corridor::ntcip {

enum class LinkState : std::uint8_t { up, degraded, unreachable };
[[nodiscard]] const char* to_string(LinkState s);  // "up", "degraded", "unreachable"

// One call on a field controller, as field systems keep it.
struct CallRecord {
  std::uint64_t id = 0;  // unique across runs: the request time in µs, made unique
  NodeId signal;
  std::string controller;
  std::vector<std::uint64_t> missions;  // whose claims the call served, the highest first
  int priority = 0;
  std::string kind;            // "preempt" or "phase_control"
  std::uint32_t preempt = 0;   // the preempt input, for a preempt
  std::string approach;        // "N", "E", "S", "W"
  double request_s = 0.0;
  std::optional<double> grant_s;    // first preemptState in service (entry, track, dwell, link)
  std::optional<double> release_s;  // Corridor removed the call
  std::optional<double> clear_s;    // the controller reports the call off and its preempt out of service
  // pending (not cleared yet), served, denied (answered, never in service), timed_out (max
  // presence), unreachable (no answer while the call was on), orphan_cleared (left by an earlier run)
  std::string outcome = "pending";
};

// What a field controller reports, and how its link stands.
struct FieldStatus {
  NodeId signal;
  std::string controller;
  LinkState link = LinkState::unreachable;
  std::string last_error;
  std::optional<double> last_answer_s;
  std::uint32_t preempt = 0;  // the preempt being called, 0 for none
  std::optional<PreemptState> preempt_state;  // the controller's own, for that preempt
  bool call_on = false;       // Corridor wants a call now
  std::vector<preemption::Light> lights;  // as it reports them; empty where its phases are not wired
  // The round trip of its answered requests (SNMP's cost per command), over the last 4,096.
  std::size_t answers = 0;
  std::optional<double> rtt_p50_ms;
  std::optional<double> rtt_p99_ms;
};

class FieldSignalController final : public preemption::SignalController {
 public:
  using Clock = std::function<double()>;
  // Throws ControllersFileError naming the controller when its intersection is not a signal of the
  // map, or its wiring does not fit the intersection. Nothing is sent before the first tick().
  FieldSignalController(const maps::RoadGraph& graph, const maps::SignalMap& signals, std::vector<ControllerConfig> controllers,
                        Clock clock);
  // Clears every call still on (waits up to 2 s for the controllers to answer).
  ~FieldSignalController() override;
  FieldSignalController(const FieldSignalController&) = delete;
  FieldSignalController& operator=(const FieldSignalController&) = delete;

  [[nodiscard]] bool controls(NodeId signal) const { return fields_.contains(signal); }
  [[nodiscard]] std::vector<NodeId> signals() const;

  void hold(NodeId node, const maps::Phase& phase, double now_s) override;
  void hold_for(NodeId node, const maps::Phase& phase, const preemption::HoldRequest& request, double now_s) override;
  void release(NodeId node, std::size_t resume_step, double now_s) override;
  [[nodiscard]] preemption::SignalMode mode(NodeId node) const override;
  // A field controller's program is its own: without a reading of what it shows, the worst case
  // (the longest minimum green of the plan) stands for what it still owes.
  [[nodiscard]] double remaining_min_green_s(NodeId node, double now_s) const override;
  [[nodiscard]] std::optional<std::size_t> current_phase(NodeId node) const override;
  [[nodiscard]] std::optional<double> green_start_s(NodeId node, std::size_t movement) const override;
  [[nodiscard]] preemption::HoldStage hold_stage(NodeId node) const override;
  [[nodiscard]] std::vector<preemption::Light> lights_shown(NodeId node) const override;

  // Sends what is due: the start-up check (orphaned calls cleared), calls and their keep-alive,
  // removals, and the state polls, each controller at its own pace and backoff. About once a second.
  void tick(double now_s);
  // Call records that changed since the last take, in the order they changed.
  [[nodiscard]] std::vector<CallRecord> take_records();
  [[nodiscard]] std::vector<FieldStatus> status() const;
  [[nodiscard]] std::optional<FieldStatus> status(NodeId signal) const;

  struct Field;

 private:
  void on_reply(Field& f, const SnmpReply& r, double now_s, double sent_s);
  void update_call(Field& f, double now_s);
  void touch(Field& f);  // a changed record goes to take_records
  [[nodiscard]] Field& field(NodeId node);
  [[nodiscard]] const Field& field(NodeId node) const;

  Clock clock_;
  std::unique_ptr<SnmpManager> snmp_;
  mutable std::mutex mutex_;  // the fields' state: the engine's calls and the SNMP thread's replies
  std::map<NodeId, std::unique_ptr<Field>> fields_;
  std::vector<CallRecord> changed_;
  std::uint64_t last_record_id_ = 0;
};

}  // namespace corridor::ntcip
