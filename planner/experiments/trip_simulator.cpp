#include "planner/experiments/trip_simulator.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>

#include "planner/one_to_one_search.hpp"

namespace corridor::planner {
namespace {

void validate(const maps::RoadGraph& g, const TripScenario& s) {
  const auto n = g.node_count();
  if (!s.source.valid() || s.source.index() >= n || !s.destination.valid() || s.destination.index() >= n) {
    throw std::invalid_argument("trip source or destination is not a node of the graph");
  }
  if (s.source == s.destination) throw std::invalid_argument("trip source and destination are the same node");
  if (s.signal_delay_s.size() != n) throw std::invalid_argument("trip needs one signal delay per node");
  for (double d : s.signal_delay_s) {
    if (!(d >= 0.0 && std::isfinite(d))) throw std::invalid_argument("signal delays must be finite and >= 0");
  }
  for (const CongestionEvent& e : s.events) {
    if (!e.edge.valid() || e.edge.index() >= g.edge_count()) throw std::invalid_argument("congestion event on an unknown edge");
    if (!(e.time_s >= 0.0 && std::isfinite(e.time_s)) || !(e.queue_delay_s >= 0.0 && std::isfinite(e.queue_delay_s))) {
      throw std::invalid_argument("congestion event times and delays must be finite and >= 0");
    }
  }
}

std::vector<CongestionEvent> sorted_events(std::vector<CongestionEvent> events) {
  std::stable_sort(events.begin(), events.end(),
                   [](const CongestionEvent& a, const CongestionEvent& b) { return a.time_s < b.time_s; });
  return events;
}

// What the planners know: the signal delays from the start, and each event from its time on.
class Knowledge {
 public:
  Knowledge(const maps::RoadGraph& g, const TripScenario& s, Signals signals)
      : overlay_(g), events_(sorted_events(s.events)) {
    if (signals == Signals::no_preemption) {
      for (NodeId v : g.nodes()) overlay_.set_node_delay(v, s.signal_delay_s[v.index()]);
    }
  }

  // Reveals the events up to `time_s`; returns the edges whose cost changed.
  std::vector<EdgeId> reveal_until(double time_s) {
    std::vector<EdgeId> changed;
    for (; next_ < events_.size() && events_[next_].time_s <= time_s; ++next_) {
      const CongestionEvent& ev = events_[next_];
      EdgeCondition c = overlay_.edge(ev.edge);
      if (c.queue_delay_s == ev.queue_delay_s) continue;
      c.queue_delay_s = ev.queue_delay_s;
      overlay_.set_edge(ev.edge, c);
      changed.push_back(ev.edge);
    }
    return changed;
  }

  [[nodiscard]] const CostOverlay& overlay() const { return overlay_; }
  [[nodiscard]] const std::vector<CongestionEvent>& events() const { return events_; }

 private:
  CostOverlay overlay_;
  std::vector<CongestionEvent> events_;
  std::size_t next_ = 0;
};

// The vehicle's clock and what it has waited for, advanced one edge at a time.
class Vehicle {
 public:
  Vehicle(const TripScenario& s, Signals signals, const TravelCost& cost, const std::vector<CongestionEvent>& events)
      : s_(s), signals_(signals), cost_(cost), events_(events), at_(s.source) {}

  void take(EdgeId e, TripResult& r) {
    const auto& g = cost_.graph();
    if (g.tail(e) != at_) throw std::logic_error("trip simulator: route is not connected");
    // The queue is the one there when the vehicle reaches the stop line and commits to the edge.
    const double queue = queue_delay_at(events_, e, time_s_);
    if (at_ != s_.source && signals_ == Signals::no_preemption) {
      time_s_ += s_.signal_delay_s[at_.index()];
      r.signal_wait_s += s_.signal_delay_s[at_.index()];
    }
    // A gate or toll booth (maps::node_stops_vehicle) holds the vehicle as long as the planner
    // expects, preempted or not.
    if (at_ != s_.source && g.stop_at(at_)) time_s_ += cost_.profile().barrier_delay_s;
    // The turn onto e costs what the planner charges for it (angle, crossing traffic).
    std::uint32_t vertex = e.v;
    if (!r.driven.empty()) {
      const auto [turn, next] = cost_.turn_onto(vertex_, e);
      if (turn >= kInfCost) throw std::logic_error("trip simulator: route takes a turn the vehicle may not make");
      time_s_ += turn;
      vertex = next;
    }
    vertex_ = vertex;
    time_s_ += cost_.running_time_s(e) + queue;
    r.queue_wait_s += queue;
    r.driven.push_back(e);
    at_ = g.head(e);
    if (r.driven.size() > 64 * g.node_count() + 1000) throw std::logic_error("trip simulator: vehicle is going round in circles");
  }

  [[nodiscard]] double time_s() const { return time_s_; }
  [[nodiscard]] NodeId at() const { return at_; }
  // The turn-graph state of the last edge driven: how a via-way restriction knows where it came from.
  [[nodiscard]] std::uint32_t vertex() const { return vertex_; }

 private:
  const TripScenario& s_;
  Signals signals_;
  const TravelCost& cost_;
  const std::vector<CongestionEvent>& events_;
  NodeId at_;
  std::uint32_t vertex_ = 0;  // the turn-graph vertex of the last edge driven
  double time_s_ = 0.0;
};

Route plan_once(const TravelCost& cost, NodeId source, NodeId destination) {
  const SearchSpace space(cost, node_departures(cost.graph(), source), node_arrivals(cost.graph(), destination));
  OneToOneSearch search;
  Route route = search.run(space, /*use_heuristic=*/false);
  if (!route.found) throw std::invalid_argument("the destination cannot be reached from the source");
  return route;
}

}  // namespace

std::vector<EdgePoint> node_departures(const maps::RoadGraph& g, NodeId v) {
  std::vector<EdgePoint> points;
  for (EdgeId e : g.out_edges(v)) points.push_back({e, 0.0});
  return points;
}

std::vector<EdgePoint> node_arrivals(const maps::RoadGraph& g, NodeId v) {
  std::vector<EdgePoint> points;
  for (EdgeId e : g.in_edges(v)) points.push_back({e, g.length_m(e)});
  return points;
}

const char* to_string(Routing r) { return r == Routing::static_route ? "static" : "dynamic"; }
const char* to_string(Signals s) { return s == Signals::preemption ? "preemption" : "none"; }

double queue_delay_at(std::span<const CongestionEvent> sorted_events, EdgeId edge, double time_s) {
  double delay = 0.0;
  for (const CongestionEvent& ev : sorted_events) {
    if (ev.time_s > time_s) break;
    if (ev.edge == edge) delay = ev.queue_delay_s;
  }
  return delay;
}

TripResult drive_trip(const maps::RoadGraph& graph, const TripScenario& scenario, Routing routing, Signals signals,
                      VehicleProfile vehicle, const ReplanObserver& observer) {
  validate(graph, scenario);
  Knowledge known(graph, scenario, signals);
  known.reveal_until(0.0);
  const TravelCost cost(graph, known.overlay(), vehicle);
  Vehicle ev(scenario, signals, cost, known.events());
  TripResult r;

  if (routing == Routing::static_route) {
    r.planned_at_departure = plan_once(cost, scenario.source, scenario.destination).edges;
    for (EdgeId e : r.planned_at_departure) ev.take(e, r);
    r.travel_time_s = ev.time_s();
    return r;
  }

  DStarLite planner(cost, node_departures(graph, scenario.source), node_arrivals(graph, scenario.destination));
  planner.replan();
  if (observer) observer(planner, cost);
  Route route = planner.route();
  if (!route.found) throw std::invalid_argument("the destination cannot be reached from the source");
  r.planned_at_departure = route.edges;
  std::vector<EdgeId> ahead = route.edges;
  std::size_t next = 0;
  while (true) {
    const EdgeId e = ahead.at(next++);
    ev.take(e, r);
    if (ev.at() == scenario.destination) break;

    // At the next stop line: take in what has appeared since, and repair the plan from here.
    const std::vector<EdgeId> changed = known.reveal_until(ev.time_s());
    planner.move_start({{e, graph.length_m(e), ev.vertex()}});
    if (!changed.empty()) planner.edges_changed(changed);
    const auto t0 = std::chrono::steady_clock::now();
    const ReplanStats stats = planner.replan();
    r.replan_wall_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    r.expanded += stats.expanded;
    if (observer) observer(planner, cost);
    if (changed.empty()) continue;  // nothing new: the plan ahead stands

    ++r.replans;
    route = planner.route();
    if (!route.found || route.edges.front() != e) throw std::logic_error("trip simulator: replanned route does not start here");
    const std::vector<EdgeId> repaired(route.edges.begin() + 1, route.edges.end());
    if (!std::equal(repaired.begin(), repaired.end(), ahead.begin() + static_cast<std::ptrdiff_t>(next), ahead.end())) {
      ++r.route_changes;
    }
    ahead = repaired;
    next = 0;
  }
  r.travel_time_s = ev.time_s();
  return r;
}

double base_travel_time_s(const maps::RoadGraph& graph, NodeId source, NodeId destination, VehicleProfile vehicle) {
  const CostOverlay overlay(graph);
  const TravelCost cost(graph, overlay, vehicle);
  return plan_once(cost, source, destination).travel_time_s;
}

Route static_plan(const maps::RoadGraph& graph, const TripScenario& scenario, Signals signals, VehicleProfile vehicle) {
  validate(graph, scenario);
  Knowledge known(graph, scenario, signals);
  const TravelCost cost(graph, known.overlay(), vehicle);
  return plan_once(cost, scenario.source, scenario.destination);
}

}  // namespace corridor::planner
