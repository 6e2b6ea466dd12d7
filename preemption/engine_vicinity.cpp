// The preemption engine's vicinity rules (the seed's future work): queues near the route, not only
// the vehicle's own approach, decide when a hold starts. The detector inputs they read (counts,
// occupancy, speed ratio, standing queues), the upstream-approach and spillback starts, and the
// flushes of side links about to spill back into the vehicle's stop line.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "maps/intersection_geometry.hpp"
#include "preemption/engine.hpp"
#include "preemption/plan_movement.hpp"

namespace corridor::preemption {

std::optional<PreemptionEngine::VicinityStart> PreemptionEngine::vicinity_start(const Crossing& c, const Crossing* previous,
                                                                                 double trans_s, double now_s) const {
  const VicinityConfig& v = config_.vicinity;
  if (!v.enabled) return std::nullopt;
  const auto it = measurements_.find(c.node);
  if (it == measurements_.end()) return std::nullopt;
  const maps::Compass from = maps::approach_side(graph_, c.in_edge);
  const std::optional<double> queue_m = it->second[static_cast<int>(from)].queue_m;
  if (!queue_m || *queue_m < v.jam_spacing_m) return std::nullopt;  // no standing vehicle
  // The queue discharges in t_q = l1 + h·n after its green (eq. 8's clearance, per lane).
  const double clearance = queue_clearance_s(*queue_m / v.jam_spacing_m, config_.timing);
  const double link_m = c.distance_m - (previous != nullptr ? previous->distance_m : 0.0);
  const double link_s = c.arrival_s - (previous != nullptr ? previous->arrival_s : now_s);
  // Upstream approach: the vehicle meets the queue's tail, not the stop line, so the queue must be
  // moving by the time it reaches the tail: τ − (tail distance)/v instead of τ in eq. 5.
  double tail_s = 0.0;
  if (link_m > 0.0 && link_s > 0.0) tail_s = std::min(*queue_m, link_m) / (link_m / link_s);
  VicinityStart best{c.arrival_s - tail_s - trans_s - config_.timing.safety_margin_s - clearance, false};
  // Downstream link of the previous signal: a queue about to spill back into that junction blocks
  // the vehicle's exit there, so this signal's outflow must be moving when the vehicle reaches the
  // previous one.
  if (previous != nullptr && link_m > 0.0 && *queue_m >= v.spillback_fraction * link_m) {
    const double flush = previous->arrival_s - trans_s - config_.timing.safety_margin_s - clearance;
    if (flush < best.start_s) best = {flush, true};
  }
  best.start_s = std::max({best.start_s, c.arrival_s - v.max_lead_s, now_s});
  return best;
}

std::vector<std::pair<NodeId, NodeId>> PreemptionEngine::update_flushes(MissionId mission, int priority,
                                                                         std::span<const Crossing> crossings, double now_s,
                                                                         std::vector<NodeId>& touched) {
  std::vector<std::pair<NodeId, NodeId>> wanted;  // (signal flushed, crossing it clears)
  const VicinityConfig& v = config_.vicinity;
  if (!v.enabled) return wanted;
  auto& entries = missions_[mission];
  for (const Crossing& c : crossings) {
    if (c.arrival_s - now_s > v.max_lead_s || exhausted_.count({mission, c.node}) != 0) continue;
    // The links leaving the vehicle's stop line other than its own: a vehicle ahead of it in its
    // lane may be bound for one of them, and stands there while that link is full.
    for (EdgeId link : graph_.out_edges(graph_.head(c.in_edge))) {
      if (link == c.out_edge) continue;
      const NodeId d = signal_node(graph_.head(link));
      const auto plan_it = plans_.find(d);
      const auto measured = measurements_.find(d);
      if (d == c.node || plan_it == plans_.end() || measured == measurements_.end()) continue;
      const maps::Compass side = maps::approach_side(graph_, link);
      const std::optional<double> queue_m = measured->second[static_cast<int>(side)].queue_m;
      if (!queue_m || *queue_m < v.spillback_fraction * graph_.length_m(link)) continue;
      const maps::SignalPlan& plan = plan_it->second;
      std::optional<std::size_t> movement;
      for (std::size_t m = 0; m < plan.movements.size() && !movement; ++m) {
        if (plan.movements[m].from == side) movement = m;
      }
      if (!movement || std::find(wanted.begin(), wanted.end(), std::pair(d, c.node)) != wanted.end()) continue;
      if (exhausted_.count({mission, d}) != 0) continue;
      wanted.emplace_back(d, c.node);
      ScheduleEntry* e = nullptr;
      for (auto& x : entries) {
        if (is_live(*x) && x->node == d && x->flush_for == c.node) e = x.get();
      }
      const bool fresh = e == nullptr;
      if (fresh) {
        entries.push_back(std::make_unique<ScheduleEntry>());
        e = entries.back().get();
        e->mission = mission;
        e->node = d;
        e->flush_for = c.node;
        e->vicinity = "side_spillback";
        e->congestion = CongestionLevel::high;
        e->movement = *movement;
        e->movement_label = plan.movements[*movement].label();
        e->phase = select_phase(plan, *movement, controller_.current_phase(d), CongestionLevel::high).phase;
      }
      e->priority = priority;
      // Its outflow moving before the vehicle reaches c: the spill-back rule, for a side link.
      const double trans = transition_time_s(controller_.remaining_min_green_s(d, now_s), plan.yellow_s, plan.all_red_s);
      const double clearance = queue_clearance_s(*queue_m / v.jam_spacing_m, config_.timing);
      e->arrival_s = c.arrival_s;
      e->natural_start_s = std::max({now_s, c.arrival_s - v.max_lead_s, c.arrival_s - trans - config_.timing.safety_margin_s - clearance});
      if (e->state == EntryState::active) e->natural_start_s = std::min(e->natural_start_s, e->started_s);
      e->release_s = c.arrival_s + config_.release_after_arrival_s;
      if (fresh) {
        nodes_[d].entries.push_back(e);
        log(now_s, mission, d, "scheduled",
            fmt::format("phase={} start_s={:.1f} arrival_s={:.1f} congestion=high vicinity=side_spillback for_node={}",
                        e->phase.label, e->natural_start_s, e->arrival_s, c.node.v),
            true);
      }
      touched.push_back(d);
    }
  }
  return wanted;
}

void PreemptionEngine::record_counts(NodeId node, maps::Compass approach, double time_s, double arrivals,
                                     double departures) {
  if (plans_.count(node) == 0) throw CountError("node " + std::to_string(node.v) + " has no signal");
  queues_[node].record(approach, time_s, arrivals, departures);
}

void PreemptionEngine::record_measurement(NodeId node, maps::Compass approach, std::optional<double> occupancy,
                                          std::optional<double> speed_ratio) {
  if (plans_.count(node) == 0) throw CountError("node " + std::to_string(node.v) + " has no signal");
  if (occupancy && !(*occupancy >= 0.0 && *occupancy <= 1.0)) throw CountError("occupancy must be within [0, 1]");
  if (speed_ratio && !(*speed_ratio >= 0.0 && std::isfinite(*speed_ratio))) {
    throw CountError("speed ratio must be a finite number >= 0");
  }
  ApproachMeasurement& m = measurements_[node][static_cast<int>(approach)];
  m.occupancy = occupancy;
  m.speed_ratio = speed_ratio;
}

void PreemptionEngine::record_queue_length(NodeId node, maps::Compass approach, double queue_m) {
  if (plans_.count(node) == 0) throw CountError("node " + std::to_string(node.v) + " has no signal");
  if (!(queue_m >= 0.0 && std::isfinite(queue_m))) throw CountError("queue length must be a finite number of metres >= 0");
  measurements_[node][static_cast<int>(approach)].queue_m = queue_m;
}

}  // namespace corridor::preemption
