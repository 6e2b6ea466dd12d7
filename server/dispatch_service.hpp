// The dispatch service: the server's engine behind one facade. It owns the live congestion overlay,
// one D* Lite planner per active mission, and the preemption engine; it persists every accepted
// change before acknowledging it and rebuilds its state from the store on start-up. Writes go
// through a group-commit queue; a position's result carries the ticket that says when it is
// durable. Transport-free, so request handling can be tested and fuzzed without sockets.
#pragma once

#include <atomic>
#include <chrono>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <shared_mutex>
#include <unordered_map>

#include "maps/edge_snapper.hpp"
#include "maps/road_graph.hpp"
#include "maps/signal_map.hpp"
#include "planner/dstar_lite.hpp"
#include "preemption/engine.hpp"
#include "ntcip/controllers_file.hpp"
#include "ntcip/field_signals.hpp"
#include "preemption/simulated_signal_controller.hpp"
#include "server/api_error.hpp"
#include "server/commit_queue.hpp"
#include "server/dispatch_types.hpp"
#include "server/json_codec.hpp"
#include "server/mission_planner.hpp"
#include "server/routed_signals.hpp"
#include "server/shared_hierarchy.hpp"
#include "server/store.hpp"
#include "server/vehicle_tracker.hpp"

namespace boost::asio {
class thread_pool;
}

namespace corridor::server {

// The graph every mission's D* Lite searches.
enum class PlannerGraph {
  // The contraction hierarchy where it came out sparse (a road network's small separators: at
  // most `max_hierarchy_density` arcs per vertex), else the turn graph.
  automatic,
  // The turn graph itself: nothing shared, no preprocessing; a repair at metro scale may re-derive
  // a large part of the city.
  turn_graph,
  // A contraction hierarchy over the turn graph, shared by all missions: each congestion batch is
  // customized once, and a mission's repair touches the few hundred vertices above its start and
  // goal. Costly on maps without small separators (a city-wide grid).
  hierarchy,
};

// The repair threads a server with `io_threads` I/O threads runs by default: half of them, at
// least one. Repairs on every I/O thread leave no core to the position reports and the commit
// queue, and a repair that waits for a core mid-way is what makes the tail: on 2 cores (Porto,
// 200 missions, 1,000 congested edges/s, 2,000 positions/s) 97.2-97.6 % of repairs finished
// within 2 ms of wall time with 2 repair threads, 99.0-99.1 % with 1, for a batch that ends about
// 10 % later (docs/routing.md).
[[nodiscard]] constexpr int default_repair_threads(int io_threads) { return io_threads > 1 ? io_threads / 2 : 1; }

struct DispatchConfig {
  double snap_max_distance_m = 200.0;
  double arrival_radius_m = 30.0;  // closer than this to the destination completes the mission
  double signal_delay_s = 15.0;    // expected delay at a signalized intersection without a plan, for routing
  // How far a position's timestamp may run ahead of the server's clock (the two clocks' skew). A
  // report further ahead is refused: taken in, it would make every later report of that vehicle
  // stale, and the vehicle would stop moving until the server restarted.
  double max_clock_ahead_s = 300.0;
  // Threads that repair missions' plans after a congestion change, the calling one included
  // (default_repair_threads says how many a server with n I/O threads takes).
  int repair_threads = 2;
  // 0, or the SCHED_FIFO priority (1..99) the repair threads take while they repair a congestion
  // batch. A repair costs under 1 ms of CPU, but on a machine whose cores are shared with position
  // reports and the commit queue it waits for them mid-repair: on 2 cores, Porto, 200 missions,
  // 2,000 positions/s, 2-3 % of repairs took over 2 ms of wall time, none with priority 1. The
  // price is position acknowledgements held behind the batch (docs/routing.md). Needs root,
  // CAP_SYS_NICE or RLIMIT_RTPRIO; without them the threads keep their scheduling, with a warning.
  int repair_realtime_priority = 0;
  // Nice steps (0..19) that the commit writer takes below the process's own priority, at which the
  // workers run (mission creation, congestion batches and their repairs, ticks); HttpServer's I/O
  // threads take ServerLimits::io_nice. Where the cores are contended a batch's repairs are then
  // served first, with no privilege needed, and the position reports (each of which repairs its
  // own mission, on its I/O thread) and the journal still progress, at nice 10 with a tenth of a
  // worker's share. On 2 cores, Porto, 200 missions, 2,000 positions/s: the batch's repairs within
  // 2 ms 98.7-98.9 % at 0, 99.6-99.7 % at 10 (docs/routing.md).
  int background_nice = 10;
  PlannerGraph planner_graph = PlannerGraph::automatic;
  // Arcs per vertex above which `automatic` keeps the turn graph: road networks measure 6 to 10, a
  // city-wide grid about 30, where customizing a batch costs 20x more (docs/routing.md).
  double max_hierarchy_density = 16.0;
  // Cost models (a profile at a top speed) the hierarchy keeps a metric for at once; a mission of
  // yet another one plans on the turn graph. Each costs a customization per congestion batch and
  // 54 bytes per arc (67 MB on Porto); top speeds are the client's to choose.
  int max_hierarchy_models = 4;
  preemption::PreemptionConfig preemption;
  // Signals driven in the field over NTCIP 1202 (corridor serve --controllers); the others run in
  // memory. Validated against the map when the service starts.
  std::vector<ntcip::ControllerConfig> field_controllers;
};

class DispatchService {
 public:
  using Listener = std::function<void(const DispatchEvent&)>;

  // `store` may be null (nothing persisted). With a store, active missions and congestion in force
  // are restored. Throws StoreError when the database cannot be read.
  DispatchService(const maps::RoadGraph& graph, DispatchConfig config, Store* store, double now_s);
  // With the map's own signal plans, each node its own signal.
  DispatchService(const maps::RoadGraph& graph, std::unordered_map<NodeId, maps::SignalPlan> plans, DispatchConfig config,
                  Store* store, double now_s);
  // With the map's own signals (a SUMO network's traffic lights, each over all its stop lines).
  DispatchService(const maps::RoadGraph& graph, maps::SignalMap signals, DispatchConfig config, Store* store, double now_s);
  ~DispatchService();

  // Every method validates its input and throws ApiError with a status and a clear message. Every
  // method but report_position returns once its writes are durable (StoreError if they failed).
  MissionView create_mission(const MissionRequest& request, double now_s);
  [[nodiscard]] MissionView mission(MissionId id) const;
  [[nodiscard]] std::vector<MissionView> missions(std::optional<MissionState> state) const;
  MissionView cancel_mission(MissionId id, double now_s);
  // Returns before its writes are durable: acknowledge only once `result.durable` says so.
  PositionResult report_position(const PositionReport& report, double now_s);
  CongestionResult report_congestion(const std::vector<CongestionUpdate>& updates, double now_s);
  // A signal's detector report for one approach (json_codec's CountsReport): counts for the queue
  // estimate, occupancy or speed ratio for the congestion classifier, a standing queue for the
  // vicinity rules. 400 for values out of range, 404 for a node without a signal.
  void report_detectors(NodeId node, const CountsReport& report, double now_s);
  // Expires congestion and drives the signals; call about once a second.
  void tick(double now_s);
  // Waits until every write so far is durable.
  void flush();
  [[nodiscard]] std::optional<CommitQueue::Stats> commit_stats() const;

  // Returns an id for unsubscribe(); a listener must be removed before it is destroyed.
  std::size_t subscribe(Listener listener);
  void unsubscribe(std::size_t id);
  [[nodiscard]] const maps::RoadGraph& graph() const { return graph_; }
  // The signals, one per controller, by key (maps::SignalMap); a signal id in the API is its key.
  [[nodiscard]] const std::unordered_map<NodeId, maps::SignalPlan>& signal_plans() const { return signals_map_.signals; }
  // The SUMO tls id of a signal, empty on an OSM map.
  [[nodiscard]] std::string signal_name(NodeId signal) const;
  // The field controller's report and link of a signal driven over NTCIP; nullopt for the others.
  [[nodiscard]] std::optional<ntcip::FieldStatus> field_status(NodeId signal) const;
  // Call records on field controllers, newest first: of one signal (404 for one that is not a
  // signal), or of one mission (404 for an unknown one), at most `limit`.
  [[nodiscard]] std::vector<SignalCallRow> signal_calls(NodeId signal, std::size_t limit);
  [[nodiscard]] std::vector<SignalCallRow> mission_calls(MissionId mission, std::size_t limit);
  [[nodiscard]] std::vector<preemption::Light> signal_lights(NodeId node) const;
  // "held" (for an emergency vehicle), "clearing" (yellow and all-red on the way back) or
  // "program", and the program step; a simulator mirrors these onto its own lights.
  [[nodiscard]] std::pair<std::string, std::size_t> signal_mode(NodeId node) const;
  [[nodiscard]] std::size_t active_mission_count() const;
  // Whether a repair thread got the real-time priority it was configured with: nullopt until one
  // has asked (or when none is configured).
  [[nodiscard]] std::optional<bool> repair_realtime_granted() const;
  // The graph the missions are planned on (never `automatic`), and the hierarchy when it is that.
  [[nodiscard]] PlannerGraph planner_graph() const { return hierarchy_ ? PlannerGraph::hierarchy : PlannerGraph::turn_graph; }
  [[nodiscard]] const SharedHierarchy* hierarchy() const { return hierarchy_.get(); }
  // What a console shows of a signal: "normal" (its program), "scheduled" (a hold is planned),
  // "held" (green for an emergency vehicle) or "recovering" (yellow and all-red back to the program).
  [[nodiscard]] std::string signal_state(NodeId node) const;
  // Every vehicle's latest accepted report, by vehicle id.
  [[nodiscard]] std::vector<VehicleView> vehicles() const;
  // The mission's route revisions, oldest first (404 for an unknown mission).
  [[nodiscard]] std::vector<RouteRevisionView> route_history(MissionId id) const;

 private:
  struct Mission;
  using MissionPtr = std::shared_ptr<Mission>;
  // The writes of one call, submitted to the commit queue together, in order, as one ticket.
  using Staged = std::vector<CommitQueue::Write>;

  // The active mission, or ApiError; the registry lock is released on return.
  MissionPtr find(MissionId id) const;
  static void require_active(const Mission& m);
  enum class Role { start, goal };
  std::vector<planner::EdgePoint> endpoints(const maps::SnapResult& snap, Role role, std::optional<double> heading_deg) const;
  // Brings a mission's plan up to date with the costs and its start (under the mission's lock);
  // returns the reason of a cost change it had not repaired yet, if any.
  std::optional<std::string> repair(Mission& m, const std::vector<planner::EdgePoint>* new_start);
  // A new route revision: persist_route stages its write; announce_route re-times the signals
  // and tells the listeners; publish_route does both. Creating a mission stores before it announces.
  void persist_route(Mission& m, const std::string& reason, double now_s, Staged& staged);
  void announce_route(Mission& m, const std::string& reason, double now_s, Staged& staged);
  void publish_route(Mission& m, const std::string& reason, double now_s, Staged& staged);
  void retime_signals(Mission& m, double now_s, Staged& staged);
  // Applies edge changes to the overlay (and customizes the hierarchy's metrics) and tells every
  // active planner of them; returns those missions. Adds the customization's time to `customization_s`.
  std::vector<MissionPtr> apply_changes(const std::vector<std::pair<EdgeId, planner::EdgeCondition>>& changes,
                                        const std::string& reason, double& customization_s);
  // Repairs those plans, spread over the repair threads, one mission lock at a time each, and
  // publishes new routes; collects the write tickets.
  CongestionResult repair_plans(const std::vector<MissionPtr>& missions, double now_s, std::chrono::steady_clock::time_point started,
                                std::vector<std::shared_ptr<CommitTicket>>& durable);
  void repair_one(Mission& m, double now_s, CongestionResult& result, std::vector<std::shared_ptr<CommitTicket>>& durable);
  // Under preemption_mutex_.
  void drain_preemption_events(Staged& staged);
  // Under preemption_mutex_: the field controllers' changed call records, stored and announced.
  void drain_call_records(Staged& staged);
  void emit(DispatchEvent event);
  // Under preemption_mutex_: emits signal_state when the signal's state changed since last said.
  void announce_signal_state(NodeId node, double now_s);
  // Under preemption_mutex_: a signal_field event for each field controller whose link, preempt
  // state or call changed since the last one (the console's live view of the controllers).
  void announce_field_states(double now_s);
  [[nodiscard]] std::string signal_state_locked(NodeId node) const;
  MissionView view(const Mission& m) const;
  static planner::VehicleProfile vehicle_profile(const MissionRow& row);
  // A planned mission's planner on the service's graph; call under the overlay's shared lock.
  MissionPlanner make_planner(const MissionRow& row, std::vector<planner::EdgePoint> starts,
                              std::vector<planner::EdgePoint> goals);
  // Plans m (its row set) from `start` to its destination, snapped to `from` and `to`, with a second
  // try from the main component's roads when an end lies on a road cut off from the rest
  // (planner::plan_nearest_or_main); `from` and `to` end at the snaps planned from. Call under the
  // overlay's shared lock. Whether a route was found.
  // How a trip's end is snapped: a click (a destination, an origin given in the request) never on a
  // ferry; a vehicle's own position fix may be on one, since it may be riding it.
  [[nodiscard]] maps::SnapOptions trip_end_snap(bool vehicle_fix) const;
  bool plan_mission(Mission& m, maps::LatLon start, maps::SnapResult& from, maps::SnapResult& to,
                    std::optional<double> heading);
  // Ends a mission in memory; the caller stores the new state (stage_state) first.
  void finish(Mission& m, MissionState state, double now_s, Staged& staged);
  void stage_state(const Mission& m, MissionState state, double now_s, Staged& staged) const;
  // Adds a write to a call's batch; without a store there is nothing to write.
  void stage(Staged& staged, CommitQueue::Write write) const;
  std::shared_ptr<CommitTicket> submit(Staged& staged);
  std::vector<EdgeId> resolve_edges(const CongestionUpdate& u) const;
  void restore(double now_s);

  // Locks, always taken in this order (never one while holding a later one):
  //   create_mutex_ | congestion_mutex_  ->  Mission::mutex  ->  overlay_mutex_  ->  SharedHierarchy's own
  //   ->  preemption_mutex_  ->  registry_mutex_  ->  Mission::pending_mutex  ->  listeners_mutex_
  // Each mission's planner is confined to its own Mission::mutex, so missions are served in parallel.
  const maps::RoadGraph& graph_;
  DispatchConfig config_;
  Store* store_;
  std::unique_ptr<CommitQueue> commits_;  // null without a store
  maps::EdgeSnapper snapper_;
  // Each vehicle's map matcher and last accepted fix; its locks are taken before, never under, ours.
  VehicleTracker tracker_;
  // The plan at every controlled node (routing costs, the route's crossings), and the signals the
  // engine and the controller hold, one per controller.
  const maps::SignalMap signals_map_;
  const std::unordered_map<NodeId, maps::SignalPlan>& plans_ = signals_map_.plans;
  std::unordered_multimap<std::int64_t, EdgeId> edges_by_way_;

  // Read by every planner's repair (shared), written by congestion changes (exclusive); the
  // hierarchy's metrics follow the overlay under the same lock.
  mutable std::shared_mutex overlay_mutex_;
  planner::CostOverlay overlay_;
  std::unique_ptr<SharedHierarchy> hierarchy_;  // null when missions plan on the turn graph

  // The signals and the engine that arbitrates between missions.
  mutable std::mutex preemption_mutex_;
  preemption::SimulatedSignalController signals_;
  std::unique_ptr<ntcip::FieldSignalController> field_;  // null without field controllers
  RoutedSignals routed_;
  preemption::PreemptionEngine preemption_;
  std::deque<SignalCallRow> recent_calls_;  // without a store: the latest call records
  std::unordered_map<NodeId, std::string> shown_signal_state_;  // last announced signal_state
  std::unordered_map<NodeId, std::string> shown_field_state_;   // last announced signal_field

  mutable std::shared_mutex registry_mutex_;
  std::map<MissionId, MissionPtr> missions_;
  std::unordered_map<std::string, MissionId> active_by_vehicle_;
  std::unordered_map<std::string, VehicleView> vehicles_;

  // Serializes mission creation (rare): one vehicle never gets two active missions.
  std::mutex create_mutex_;
  MissionId next_mission_id_ = 1;  // after the highest stored id

  // Serializes congestion changes and expiries end to end, so that the database and the planners
  // see the same order; guards the expiry bookkeeping.
  std::mutex congestion_mutex_;
  // Expiry time -> (edge, update sequence); an expiry resets the edge only if it belongs to the
  // edge's latest update.
  std::multimap<double, std::pair<EdgeId, std::uint64_t>> expiries_;
  std::unordered_map<EdgeId, std::uint64_t> latest_update_;
  std::uint64_t update_sequence_ = 0;

  std::unique_ptr<boost::asio::thread_pool> repair_pool_;  // null with one repair thread
  enum class Realtime : int { not_asked, granted, denied };
  std::atomic<Realtime> repair_realtime_{Realtime::not_asked};

  mutable std::mutex listeners_mutex_;
  std::map<std::size_t, Listener> listeners_;
  std::size_t next_listener_ = 1;
  std::uint64_t next_event_seq_ = 1;
};

}  // namespace corridor::server
