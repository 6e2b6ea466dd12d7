// The preemption engine: for every signalized intersection on each emergency vehicle's route it
// picks the phase, times the start (Gedawy's equations), arbitrates between vehicles, drives the
// SignalController, and restores the normal program behind the vehicle. Time is the caller's.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <map>
#include <set>
#include <memory>
#include <span>
#include <string>
#include <unordered_map>
#include <vector>

#include "maps/road_graph.hpp"
#include "maps/signal_plan.hpp"
#include "planner/route.hpp"
#include "preemption/congestion_classifier.hpp"
#include "preemption/phase_selection.hpp"
#include "preemption/queue_estimator.hpp"
#include "preemption/signal_controller.hpp"
#include "preemption/timing.hpp"

namespace corridor::preemption {

using MissionId = std::uint64_t;

// Vicinity-aware preemption (the seed's future work): queues near the route, not only the vehicle's
// own approach, decide when a hold starts. Both rules need a measured standing queue
// (record_queue_length); without one they change nothing, and with `enabled` false the engine is
// the seed's route-only preemption. Where a rule applies, the hold serves the vehicle's whole
// approach (the seed's high-congestion phase), so the queue moves whatever its vehicles' turns.
struct VicinityConfig {
  bool enabled = false;
  double jam_spacing_m = 7.5;       // metres of lane per queued vehicle
  // A queue filling this share of the link from the previous signal on the route is about to spill
  // back into that junction and block the vehicle's exit there.
  double spillback_fraction = 0.6;
  // No vicinity rule starts a hold more than this before the vehicle's arrival, so that an early
  // hold stays far inside max_hold_s.
  double max_lead_s = 90.0;
};

struct PreemptionConfig {
  TimingConfig timing;
  CongestionClassifierConfig congestion;
  double release_after_arrival_s = 8.0;  // planned release: the vehicle is through the junction
  double max_overrun_s = 60.0;           // a vehicle this late past its predicted arrival: expire
  double max_hold_s = 180.0;             // no hold lasts longer than this, whatever happens
  double release_grace_s = 15.0;         // an active hold this long past its planned release ends
  VicinityConfig vicinity;
};

// One signalized intersection on a route.
struct Crossing {
  NodeId node;
  EdgeId in_edge;
  EdgeId out_edge;
  double arrival_s = 0;  // predicted arrival at the stop line, absolute time
  double distance_m = 0;  // along the route from the vehicle to the stop line
};

// The signalized crossings of a planned route, with arrivals relative to `now_s`.
std::vector<Crossing> signalized_crossings(const maps::RoadGraph& graph, const planner::Route& route,
                                           const std::unordered_map<NodeId, maps::SignalPlan>& plans, double now_s);

enum class EntryState { planned, active, released, cancelled, expired };
const char* to_string(EntryState s);

struct ScheduleEntry {
  MissionId mission = 0;
  int priority = 0;
  NodeId node;
  std::size_t movement = 0;
  std::string movement_label;
  // Every movement the vehicle makes at this signal, in order: one, or one per stop line where a
  // light controls several joined junctions and the route crosses them one after the other.
  std::vector<std::size_t> movements;
  // The stop lines (their approach edges) the vehicle has still to cross under this hold; the hold
  // is released once it has crossed the last.
  std::vector<EdgeId> lines;
  maps::Phase phase;
  CongestionLevel congestion = CongestionLevel::low;
  double natural_start_s = 0;  // from the timing equations alone
  double start_s = 0;          // after arbitration
  double started_s = 0;        // when the hold began (active entries)
  double arrival_s = 0;
  double release_s = 0;
  EntryState state = EntryState::planned;
  bool deferred = false;  // lost arbitration: served right after the winner
  // Why a vicinity rule moved the start earlier: "approach_queue", "spillback", or
  // "side_spillback" for a flush of a link off the route; empty otherwise.
  std::string vicinity;
  // The start was moved earlier because the controller foresees its program changing before then.
  bool foreseen = false;
  // A side-link flush: the crossing on the route whose blocking it clears (released when the
  // vehicle passes that crossing); empty for the route's own holds.
  std::optional<NodeId> flush_for;
};

// Planned or active: the entry still has a hold to give.
[[nodiscard]] inline bool is_live(const ScheduleEntry& e) { return e.state == EntryState::planned || e.state == EntryState::active; }

struct PreemptionEvent {
  double time_s;
  MissionId mission;
  NodeId node;
  std::string kind;  // scheduled, retimed, started, released, cancelled, expired, deferred
  std::string detail;  // key=value pairs
  bool side_flush = false;  // about a side-link flush, not one of the vehicle's own crossings
};

class PreemptionEngine {
 public:
  PreemptionEngine(const maps::RoadGraph& graph, const std::unordered_map<NodeId, maps::SignalPlan>& plans,
                   SignalController& controller, PreemptionConfig config = {});

  // The mission's current route (after every replan): re-times its crossings, schedules new ones,
  // and cancels those the route no longer crosses.
  void update_route(MissionId mission, int priority, std::span<const Crossing> crossings, double now_s);
  // The vehicle cleared the stop line: release the signal behind it.
  void vehicle_passed(MissionId mission, NodeId node, double now_s);
  void cancel(MissionId mission, double now_s);
  // Drops a mission whose entries are all finished (after cancel or completion), so a long-running
  // server does not keep every schedule it ever made. Live entries are cancelled first.
  void forget(MissionId mission, double now_s);
  // Detector counts for the queue estimate. Throws CountError for bad counts.
  void record_counts(NodeId node, maps::Compass approach, double time_s, double arrivals, double departures);
  // Occupancy (0..1) or measured/free speed ratio of an approach, for the congestion classifier
  // where no queue estimate exists. Throws CountError for values outside their range.
  void record_measurement(NodeId node, maps::Compass approach, std::optional<double> occupancy,
                          std::optional<double> speed_ratio);
  // The standing queue on an approach, in metres back from the stop line (the longest lane's, as a
  // lane-area detector's jam length reports it): the vicinity rules' input. Throws CountError for
  // a negative or non-finite length or a node without a signal.
  void record_queue_length(NodeId node, maps::Compass approach, double queue_m);
  // Where several graph nodes are one signal (a SUMO light's stop lines), each node's signal node,
  // the key of `plans`; nodes not listed are their own.
  void set_signal_nodes(std::unordered_map<NodeId, NodeId> signal_of);
  // Starts holds whose time has come, expires overdue ones, and releases signals no one holds.
  void tick(double now_s);

  [[nodiscard]] std::vector<ScheduleEntry> schedule(MissionId mission) const;
  [[nodiscard]] std::vector<PreemptionEvent> take_events();
  [[nodiscard]] bool holding(NodeId node) const;
  // True when a live entry of some mission plans a hold at the node that has not started yet.
  [[nodiscard]] bool planned(NodeId node) const;

 private:
  struct NodeState {
    std::vector<ScheduleEntry*> entries;       // live (planned or active) entries of all missions
    std::vector<std::uint8_t> held;            // the green set being held; empty when not holding
    HoldRequest held_for;                      // whom the hold serves
    std::vector<std::uint8_t> red_while_held;  // movements kept red by the holds, for recovery
  };

  // False when the crossing has no movement in the plan (a U-turn into the approach it came from).
  // `group` is the route's consecutive crossings of one signal (one, unless the signal controls
  // several joined junctions), `previous` the signalized crossing before them, if any.
  bool time_entry(ScheduleEntry& e, std::span<const Crossing> group, const Crossing* previous, double now_s);
  // The latest start from which the controller, running its program until then, shows every
  // movement of `e` green by `green_by_s`; nullopt where it cannot foresee its program that far.
  [[nodiscard]] std::optional<double> foreseen_start(const ScheduleEntry& e, double green_by_s, double now_s) const;
  // The vicinity rules' start for a crossing, and which rule set it; nullopt when neither applies.
  struct VicinityStart {
    double start_s;
    bool spillback;
  };
  // Vicinity, side links: flushes of the lights whose approach is a link leaving the vehicle's stop
  // line off its route and about to spill back into it. Schedules and re-times them; returns the
  // (signal, crossing) pairs wanted now. Nodes it changed go to `touched`.
  std::vector<std::pair<NodeId, NodeId>> update_flushes(MissionId mission, int priority, std::span<const Crossing> crossings,
                                                        double now_s, std::vector<NodeId>& touched);
  [[nodiscard]] NodeId signal_node(NodeId node) const;
  [[nodiscard]] std::optional<VicinityStart> vicinity_start(const Crossing& c, const Crossing* previous, double trans_s,
                                                            double now_s) const;
  void arbitrate(NodeId node, double now_s);
  void finish(ScheduleEntry& e, EntryState state, double now_s, const std::string& detail);
  void refresh_node(NodeId node, double now_s);
  [[nodiscard]] std::size_t recovery_step(NodeId node, const NodeState& ns, double now_s) const;
  void log(double t, MissionId m, NodeId n, std::string kind, std::string detail, bool side_flush = false);

  const maps::RoadGraph& graph_;
  const std::unordered_map<NodeId, maps::SignalPlan>& plans_;
  SignalController& controller_;
  PreemptionConfig config_;
  std::map<MissionId, std::vector<std::unique_ptr<ScheduleEntry>>> missions_;
  std::unordered_map<NodeId, NodeState> nodes_;
  std::unordered_map<NodeId, QueueEstimator> queues_;
  std::unordered_map<NodeId, std::array<ApproachMeasurement, 4>> measurements_;
  std::vector<PreemptionEvent> events_;
  // (mission, signal) pairs whose hold hit max_hold_s: never held again for that mission, so a
  // stuck vehicle cannot keep a junction by re-scheduling.
  std::set<std::pair<MissionId, NodeId>> exhausted_;
  std::unordered_map<NodeId, NodeId> signal_of_;
};

}  // namespace corridor::preemption
