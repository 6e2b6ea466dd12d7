#include "preemption/engine.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <utility>

#include "maps/intersection_geometry.hpp"
#include "preemption/plan_movement.hpp"

namespace corridor::preemption {
namespace {

// Arbitration order: a vehicle's own crossing before any side-link flush, then mission priority
// (higher first), then predicted arrival, then mission id.
bool serves_first(const ScheduleEntry* a, const ScheduleEntry* b) {
  if (a->flush_for.has_value() != b->flush_for.has_value()) return !a->flush_for.has_value();
  if (a->priority != b->priority) return a->priority > b->priority;
  if (a->arrival_s != b->arrival_s) return a->arrival_s < b->arrival_s;
  return a->mission < b->mission;
}

bool phases_conflict(const maps::SignalPlan& plan, const maps::Phase& a, const maps::Phase& b) {
  for (std::size_t m = 0; m < plan.movements.size(); ++m) {
    if (!a.serves(m)) continue;
    for (std::size_t k = 0; k < plan.movements.size(); ++k) {
      if (b.serves(k) && plan.conflicts(m, k)) return true;
    }
  }
  return false;
}

std::string fmt_s(double t) {
  std::ostringstream out;
  out.precision(1);
  out << std::fixed << t;
  return out.str();
}

}  // namespace

const char* to_string(EntryState s) {
  switch (s) {
    case EntryState::planned: return "planned";
    case EntryState::active: return "active";
    case EntryState::released: return "released";
    case EntryState::cancelled: return "cancelled";
    case EntryState::expired: return "expired";
  }
  return "?";
}

std::vector<Crossing> signalized_crossings(const maps::RoadGraph& graph, const planner::Route& route,
                                           const std::unordered_map<NodeId, maps::SignalPlan>& plans, double now_s) {
  std::vector<Crossing> out;
  double distance = route.edges.empty() ? 0.0 : -route.start.offset_m;
  for (std::size_t i = 0; i < route.nodes.size() && i + 1 < route.edges.size(); ++i) {
    distance += graph.length_m(route.edges[i]);
    if (plans.count(route.nodes[i]) == 0) continue;
    out.push_back({route.nodes[i], route.edges[i], route.edges[i + 1], now_s + route.arrival_s[i], std::max(0.0, distance)});
  }
  return out;
}

PreemptionEngine::PreemptionEngine(const maps::RoadGraph& graph, const std::unordered_map<NodeId, maps::SignalPlan>& plans,
                                   SignalController& controller, PreemptionConfig config)
    : graph_(graph), plans_(plans), controller_(controller), config_(config) {}

void PreemptionEngine::log(double t, MissionId m, NodeId n, std::string kind, std::string detail, bool side_flush) {
  spdlog::info("event=preemption_{} t={:.1f} mission={} node={} {}", kind, t, m, n.v, detail);
  events_.push_back({t, m, n, std::move(kind), std::move(detail), side_flush});
}

std::optional<double> PreemptionEngine::foreseen_start(const ScheduleEntry& e, double green_by_s, double now_s) const {
  if (green_by_s <= now_s) return std::nullopt;
  const maps::SignalPlan& plan = plans_.at(e.node);
  const std::vector<ProgramInterval> forecast = controller_.program_forecast(e.node, now_s, green_by_s - now_s);
  if (forecast.empty()) return std::nullopt;
  const auto serves = [&](const std::vector<std::uint8_t>& green) {
    return std::all_of(e.movements.begin(), e.movements.end(), [&](std::size_t m) { return m < green.size() && green[m]; });
  };
  const double clear_s = plan.yellow_s + plan.all_red_s;
  // A hold that starts while its movements are green keeps them green. One that starts where they
  // are red ends the phase on show once its minimum green is served, then clears: Trans.
  const double step_s = config_.timing.safety_margin_s;  // the hold starts a tick or two before a program change
  std::optional<double> latest;
  for (const ProgramInterval& iv : forecast) {
    if (iv.start_s > green_by_s) break;
    const double lo = std::max(iv.start_s, now_s);
    double candidate = -1.0;
    if (serves(iv.green)) {
      // Through the interval; before its end, so that the program's own change is not begun.
      candidate = std::min(green_by_s, iv.end_s - step_s);
    } else if (iv.clearance) {
      // The held phase takes green as the clearance ends.
      if (iv.end_s <= green_by_s) candidate = std::min(iv.end_s, green_by_s) - step_s;
    } else if (iv.min_green_end_s + clear_s <= green_by_s) {
      candidate = std::min(iv.end_s - step_s, green_by_s - clear_s);
    }
    if (candidate >= lo) latest = std::max(latest.value_or(candidate), candidate);
  }
  // The forecast covers the whole wait and no start in it is late enough: the hold must begin now.
  if (!latest && forecast.back().end_s >= green_by_s) return now_s;
  return latest;
}

bool PreemptionEngine::time_entry(ScheduleEntry& e, std::span<const Crossing> group, const Crossing* previous, double now_s) {
  const Crossing& c = group.front();
  const maps::SignalPlan& plan = plans_.at(c.node);
  const maps::Compass from = maps::approach_side(graph_, c.in_edge);
  const std::optional<std::size_t> movement = plan_movement(graph_, plan, c.in_edge, c.out_edge);
  if (!movement) return false;
  e.node = c.node;
  e.movement = *movement;
  e.movement_label = plan.movements[*movement].label();
  e.arrival_s = c.arrival_s;
  e.movements = {*movement};
  e.lines.clear();
  for (const Crossing& g : group) {
    e.lines.push_back(g.in_edge);
    if (&g == &c) continue;
    const std::optional<std::size_t> m = plan_movement(graph_, plan, g.in_edge, g.out_edge);
    if (m && std::find(e.movements.begin(), e.movements.end(), *m) == e.movements.end()) e.movements.push_back(*m);
  }
  // The phase also serves every movement that shares a lane with one of the vehicle's, so that no
  // vehicle ahead of it waits at a red the hold keeps (a through car in a shared left lane).
  std::vector<std::size_t> with(e.movements.begin() + 1, e.movements.end());
  if (!plan.lane_mates.empty()) {
    for (std::size_t m : e.movements) {
      if (m >= plan.lane_mates.size()) continue;
      for (std::size_t mate : plan.lane_mates[m]) {
        if (std::find(e.movements.begin(), e.movements.end(), mate) == e.movements.end() &&
            std::find(with.begin(), with.end(), mate) == with.end()) {
          with.push_back(mate);
        }
      }
    }
  }
  const std::span<const std::size_t> also(with);

  const QueueEstimator* queue = nullptr;
  if (auto it = queues_.find(c.node); it != queues_.end() && it->second.has_data(from)) queue = &it->second;
  ApproachMeasurement measured;
  if (auto it = measurements_.find(c.node); it != measurements_.end()) measured = it->second[static_cast<int>(from)];
  if (queue != nullptr) measured.queue_veh = queue->queue_now(from);
  e.congestion = classify_congestion(measured, config_.congestion);
  // A standing queue in front of the vehicle, or a link about to spill back, is flushed with every
  // movement of its approach, whatever turns the queued vehicles make: a queued vehicle waiting on
  // a red turn would otherwise block the vehicle's lane for the whole hold (seen in cologne8,
  // where the EV stood 180 s at its own green). The transition estimate for the rules is the worst
  // case, a full Trans.
  const double full_trans =
      transition_time_s(controller_.remaining_min_green_s(c.node, now_s), plan.yellow_s, plan.all_red_s);
  const std::optional<VicinityStart> vicinity = vicinity_start(c, previous, full_trans, now_s);
  if (vicinity) e.congestion = CongestionLevel::high;
  // Measured demand per movement (the queue on its approach) where detectors report it.
  std::vector<double> demand(plan.movements.size(), std::nan(""));
  if (auto it = queues_.find(c.node); it != queues_.end()) {
    for (std::size_t m = 0; m < plan.movements.size(); ++m) {
      if (it->second.has_data(plan.movements[m].from)) demand[m] = it->second.queue_now(plan.movements[m].from);
    }
  }

  // An active hold keeps its phase unless the vehicle's movements changed.
  const bool keep = e.state == EntryState::active &&
                    std::all_of(e.movements.begin(), e.movements.end(), [&](std::size_t m) { return e.phase.serves(m); });
  const PhaseDecision decision =
      select_phase(plan, e.movement, controller_.current_phase(c.node), e.congestion, demand, also);
  if (!keep) e.phase = decision.phase;

  // Gedawy: p = τ − Trans − margin (− t_q(τ) under congestion).
  const double trans = decision.extend || keep
                           ? 0.0
                           : transition_time_s(controller_.remaining_min_green_s(c.node, now_s), plan.yellow_s, plan.all_red_s);
  double clearance = 0.0;
  if (e.congestion == CongestionLevel::high && queue != nullptr) {
    QueueInputs q;
    q.arrivals_at_tau = queue->arrivals_at(from, e.arrival_s);
    const std::optional<double> green_start = controller_.green_start_s(c.node, e.movement);
    q.green_on = green_start.has_value();
    q.green_start_s = green_start.value_or(now_s);
    q.departures_at_green_start = queue->departures_at(from, q.green_start_s);
    q.departures_at_green_end = queue->departures_at(from, now_s);
    clearance = queue_clearance_s(queue_at_arrival_veh(e.arrival_s, q, config_.timing), config_.timing);
  }
  e.natural_start_s = std::max(now_s, preemption_start_s(e.arrival_s, trans, clearance, config_.timing));
  // Trans is what the phase on show needs now; the program may change before the start comes: end
  // the green that serves the vehicle just before its arrival, or begin a phase whose minimum green
  // outlasts the start. Where the controller foresees its program, the start is the latest one that
  // still has the vehicle's movements green by then, if that is earlier.
  if (!keep && e.state != EntryState::active) {
    if (const auto foreseen = foreseen_start(e, e.arrival_s - config_.timing.safety_margin_s - clearance, now_s)) {
      if (*foreseen < e.natural_start_s - 1e-9) {
        e.natural_start_s = std::max(now_s, *foreseen);
        e.foreseen = true;
      } else {
        e.foreseen = false;
      }
    }
  }
  e.vicinity.clear();
  if (vicinity && vicinity->start_s < e.natural_start_s) {
    e.natural_start_s = vicinity->start_s;
    e.vicinity = vicinity->spillback ? "spillback" : "approach_queue";
  }
  if (e.state == EntryState::active) e.natural_start_s = std::min(e.natural_start_s, e.started_s);
  e.release_s = group.back().arrival_s + config_.release_after_arrival_s;
  return true;
}

void PreemptionEngine::arbitrate(NodeId node, double now_s) {
  NodeState& ns = nodes_[node];
  const maps::SignalPlan& plan = plans_.at(node);
  std::sort(ns.entries.begin(), ns.entries.end(), serves_first);
  std::vector<const ScheduleEntry*> accepted;
  for (ScheduleEntry* e : ns.entries) {
    const bool was_deferred = e->deferred;
    e->start_s = e->natural_start_s;
    e->deferred = false;
    // Each claim waits for every conflicting claim ahead of it, even one already holding: a
    // higher-priority vehicle takes the signal, and the one it displaces is served right after.
    for (bool moved = true; moved;) {
      moved = false;
      for (const ScheduleEntry* a : accepted) {
        // A hold already on keeps the junction until the higher claim's own start comes.
        if (e->state == EntryState::active && a->start_s > now_s) continue;
        const bool overlap = e->start_s < a->release_s && a->start_s < e->release_s;
        if (overlap && phases_conflict(plan, e->phase, a->phase)) {
          e->start_s = a->release_s + plan.yellow_s + plan.all_red_s;
          e->release_s = std::max(e->release_s, e->start_s + config_.release_after_arrival_s);
          e->deferred = moved = true;
        }
      }
    }
    if (e->deferred && e->state == EntryState::active && e->start_s > now_s) e->state = EntryState::planned;
    if (e->deferred && !was_deferred) {
      log(now_s, e->mission, node, "deferred",
          "phase=" + e->phase.label + " start_s=" + fmt_s(e->start_s) + " reason=conflicting_higher_claim" +
              (e->flush_for ? " flush_for=" + std::to_string(e->flush_for->v) : ""),
          e->flush_for.has_value());
    }
    accepted.push_back(e);
  }
}

std::size_t PreemptionEngine::recovery_step(NodeId node, const NodeState& ns, double) const {
  // Documented recovery phase: the program step serving the approach with the longest measured
  // queue; without detector data, the step serving most of the movements the hold kept red.
  const maps::SignalPlan& plan = plans_.at(node);
  std::vector<double> weight(plan.movements.size(), 0.0);
  bool measured = false;
  if (auto it = queues_.find(node); it != queues_.end()) {
    for (std::size_t m = 0; m < plan.movements.size(); ++m) {
      if (it->second.has_data(plan.movements[m].from)) {
        weight[m] = it->second.queue_now(plan.movements[m].from);
        measured = measured || weight[m] > 0.0;
      }
    }
  }
  if (!measured) {
    for (std::size_t m = 0; m < plan.movements.size(); ++m) weight[m] = m < ns.red_while_held.size() ? ns.red_while_held[m] : 0;
  }
  std::size_t best = 0;
  double best_score = -1.0;
  for (std::size_t step = 0; step < plan.program.size(); ++step) {
    double score = 0.0;
    for (std::size_t m = 0; m < plan.movements.size(); ++m) {
      if (plan.phases[plan.program[step].phase].serves(m)) score = measured ? std::max(score, weight[m]) : score + weight[m];
    }
    if (score > best_score) {
      best_score = score;
      best = step;
    }
  }
  return best;
}

void PreemptionEngine::refresh_node(NodeId node, double now_s) {
  NodeState& ns = nodes_[node];
  const maps::SignalPlan& plan = plans_.at(node);
  std::vector<std::uint8_t> want(plan.movements.size(), 0);
  std::string label;
  double min_green = 0.0;
  HoldRequest request;  // entries are in arbitration order: the highest claim first
  for (ScheduleEntry* e : ns.entries) {
    if (e->start_s > now_s) continue;
    // Arbitration made every overlapping pair compatible, so the union of their phases is safe.
    if (phases_conflict(plan, e->phase, maps::Phase{"", want, 0.0})) continue;
    if (e->state == EntryState::planned) {
      e->state = EntryState::active;
      e->started_s = now_s;
      log(now_s, e->mission, node, "started",
          "phase=" + e->phase.label + " arrival_s=" + fmt_s(e->arrival_s) + " movement=" + e->movement_label +
              (e->flush_for ? " flush_for=" + std::to_string(e->flush_for->v) : ""),
          e->flush_for.has_value());
    }
    for (std::size_t m = 0; m < want.size(); ++m) want[m] = want[m] || e->phase.serves(m);
    if (label.find(e->phase.label) == std::string::npos) label += (label.empty() ? "" : "|") + e->phase.label;
    min_green = std::max(min_green, e->phase.min_green_s);
    for (std::size_t m : e->movements) {
      if (std::find(request.movements.begin(), request.movements.end(), m) == request.movements.end()) request.movements.push_back(m);
    }
    if (std::find(request.missions.begin(), request.missions.end(), e->mission) == request.missions.end()) {
      request.missions.push_back(e->mission);
    }
    request.priority = std::max(request.priority, e->priority);
  }
  const bool any = std::find(want.begin(), want.end(), 1) != want.end();
  if (any) {
    if (ns.red_while_held.empty()) ns.red_while_held.assign(want.size(), 0);
    for (std::size_t m = 0; m < want.size(); ++m) ns.red_while_held[m] = ns.red_while_held[m] || !want[m];
    if (want != ns.held || request.missions != ns.held_for.missions || request.movements != ns.held_for.movements) {
      controller_.hold_for(node, maps::Phase{label, want, min_green}, request, now_s);
      ns.held = want;
      ns.held_for = std::move(request);
    }
  } else if (!ns.held.empty()) {
    const std::size_t step = recovery_step(node, ns, now_s);
    controller_.release(node, step, now_s);
    log(now_s, 0, node, "recovered", "resume_step=" + std::to_string(step));
    ns.held.clear();
    ns.held_for = {};
    ns.red_while_held.clear();
  }
}

void PreemptionEngine::finish(ScheduleEntry& e, EntryState state, double now_s, const std::string& detail) {
  e.state = state;
  auto& list = nodes_[e.node].entries;
  list.erase(std::remove(list.begin(), list.end(), &e), list.end());
  log(now_s, e.mission, e.node, to_string(state), detail, e.flush_for.has_value());
}

void PreemptionEngine::update_route(MissionId mission, int priority, std::span<const Crossing> crossings, double now_s) {
  auto& entries = missions_[mission];
  std::vector<NodeId> touched;
  std::vector<NodeId> on_route;
  const Crossing* previous = nullptr;
  for (std::size_t i = 0; i < crossings.size();) {
    // The run of consecutive crossings of one signal: one hold serves them all, so that a light over
    // several joined junctions is not released and taken again between two of its stop lines.
    std::size_t j = i + 1;
    while (j < crossings.size() && crossings[j].node == crossings[i].node) ++j;
    const std::span<const Crossing> group = crossings.subspan(i, j - i);
    const Crossing& c = group.front();
    const Crossing* previous_crossing = std::exchange(previous, &crossings[j - 1]);
    i = j;
    if (plans_.count(c.node) == 0 || std::find(on_route.begin(), on_route.end(), c.node) != on_route.end()) continue;
    if (exhausted_.count({mission, c.node}) != 0) continue;
    on_route.push_back(c.node);
    ScheduleEntry* existing = nullptr;
    for (auto& e : entries) {
      if (e->node == c.node && is_live(*e) && !e->flush_for) existing = e.get();
    }
    if (existing != nullptr) {
      const double before = existing->natural_start_s;
      existing->priority = priority;
      if (!time_entry(*existing, group, previous_crossing, now_s)) {
        finish(*existing, EntryState::cancelled, now_s, "reason=no_movement");
      } else if (std::abs(existing->natural_start_s - before) > 0.5) {
        log(now_s, mission, c.node, "retimed",
            "start_s=" + fmt_s(existing->natural_start_s) + " arrival_s=" + fmt_s(existing->arrival_s) +
                (existing->foreseen ? " foreseen=program" : ""));
      }
    } else {
      auto e = std::make_unique<ScheduleEntry>();
      e->mission = mission;
      e->priority = priority;
      if (!time_entry(*e, group, previous_crossing, now_s)) continue;
      log(now_s, mission, c.node, "scheduled",
          "phase=" + e->phase.label + " start_s=" + fmt_s(e->natural_start_s) + " arrival_s=" + fmt_s(e->arrival_s) +
              " congestion=" + (e->congestion == CongestionLevel::high ? "high" : "low") +
              (e->vicinity.empty() ? "" : " vicinity=" + e->vicinity) + (e->foreseen ? " foreseen=program" : "") +
              (e->lines.size() > 1 ? " stop_lines=" + std::to_string(e->lines.size()) : ""));
      nodes_[c.node].entries.push_back(e.get());
      entries.push_back(std::move(e));
    }
    touched.push_back(c.node);
  }
  const std::vector<std::pair<NodeId, NodeId>> flushes = update_flushes(mission, priority, crossings, now_s, touched);
  for (auto& e : entries) {
    if (!is_live(*e)) continue;
    if (e->flush_for) {
      // A flush already on keeps going until the vehicle passes (or the bounds end it): its own
      // outflow draining the queue is no reason to hand the light back and take it again.
      const bool wanted = std::find(flushes.begin(), flushes.end(), std::pair(e->node, *e->flush_for)) != flushes.end();
      if (!wanted && e->state == EntryState::planned) {
        finish(*e, EntryState::cancelled, now_s, "reason=side_flush_no_longer_wanted");
        touched.push_back(e->node);
      }
    } else if (std::find(on_route.begin(), on_route.end(), e->node) == on_route.end()) {
      finish(*e, EntryState::cancelled, now_s, "reason=route_left_intersection");
      touched.push_back(e->node);
    }
  }
  for (NodeId n : touched) {
    arbitrate(n, now_s);
    refresh_node(n, now_s);
  }
}

NodeId PreemptionEngine::signal_node(NodeId node) const {
  const auto it = signal_of_.find(node);
  return it == signal_of_.end() ? node : it->second;
}

void PreemptionEngine::set_signal_nodes(std::unordered_map<NodeId, NodeId> signal_of) { signal_of_ = std::move(signal_of); }

void PreemptionEngine::vehicle_passed(MissionId mission, NodeId node, double now_s) {
  auto it = missions_.find(mission);
  if (it == missions_.end()) return;
  std::vector<NodeId> touched;
  for (auto& e : it->second) {
    if (!is_live(*e)) continue;
    // A light over several joined junctions holds until the vehicle has crossed its last stop line.
    if (e->node == node && !e->flush_for && e->lines.size() > 1) {
      e->lines.erase(e->lines.begin());
      log(now_s, mission, node, "line_crossed", "stop_lines_left=" + std::to_string(e->lines.size()));
      continue;
    }
    // Its own hold at the node, and the side links flushed for it there.
    if ((e->node == node && !e->flush_for) || e->flush_for == node) {
      finish(*e, EntryState::released, now_s, "reason=vehicle_cleared_stop_line");
      touched.push_back(e->node);
    }
  }
  for (NodeId n : touched) {
    arbitrate(n, now_s);
    refresh_node(n, now_s);
  }
}

void PreemptionEngine::cancel(MissionId mission, double now_s) {
  auto it = missions_.find(mission);
  if (it == missions_.end()) return;
  for (auto& e : it->second) {
    if (!is_live(*e)) continue;
    finish(*e, EntryState::cancelled, now_s, "reason=mission_cancelled");
    arbitrate(e->node, now_s);
    refresh_node(e->node, now_s);
  }
}

void PreemptionEngine::forget(MissionId mission, double now_s) {
  cancel(mission, now_s);
  missions_.erase(mission);
  for (auto it = exhausted_.begin(); it != exhausted_.end();) {
    it = it->first == mission ? exhausted_.erase(it) : std::next(it);
  }
}

void PreemptionEngine::tick(double now_s) {
  for (auto& [node, ns] : nodes_) {
    // Copy: finish() edits the list.
    const std::vector<ScheduleEntry*> live = ns.entries;
    for (ScheduleEntry* e : live) {
      // Bounded recovery: a vehicle that never arrives cannot hold a signal for long.
      if (now_s > e->arrival_s + config_.max_overrun_s) {
        finish(*e, EntryState::expired, now_s, "reason=vehicle_overdue");
      } else if (e->state == EntryState::active && now_s > e->started_s + config_.max_hold_s) {
        // A flush that ran out does not bar the vehicle's own later hold at that light.
        if (!e->flush_for) exhausted_.insert({e->mission, e->node});
        finish(*e, EntryState::expired, now_s, "reason=max_hold");
      } else if (e->state == EntryState::active && now_s > e->release_s + config_.release_grace_s) {
        // Re-timed on every replan, release_s runs ahead of a vehicle that reports; one that went
        // silent after the junction does not keep it.
        finish(*e, EntryState::expired, now_s, "reason=release_time_passed");
      }
    }
    arbitrate(node, now_s);
    refresh_node(node, now_s);
  }
}

std::vector<ScheduleEntry> PreemptionEngine::schedule(MissionId mission) const {
  std::vector<ScheduleEntry> out;
  if (auto it = missions_.find(mission); it != missions_.end()) {
    for (const auto& e : it->second) out.push_back(*e);
  }
  std::sort(out.begin(), out.end(), [](const ScheduleEntry& a, const ScheduleEntry& b) { return a.arrival_s < b.arrival_s; });
  return out;
}

std::vector<PreemptionEvent> PreemptionEngine::take_events() {
  std::vector<PreemptionEvent> out;
  out.swap(events_);
  return out;
}

bool PreemptionEngine::planned(NodeId node) const {
  auto it = nodes_.find(node);
  if (it == nodes_.end()) return false;
  return std::any_of(it->second.entries.begin(), it->second.entries.end(),
                     [](const ScheduleEntry* e) { return e->state == EntryState::planned; });
}

bool PreemptionEngine::holding(NodeId node) const {
  auto it = nodes_.find(node);
  return it != nodes_.end() && !it->second.held.empty();
}

}  // namespace corridor::preemption
