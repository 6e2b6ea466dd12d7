// What a signalized crossing costs a route, per movement, by one rule shared by the server and the
// SUMO loop. Where Corridor will preempt the light, the EV meets at most the transition to its
// green: the seed's Trans (remaining minimum green, yellow, all-red), averaged over the normal
// cycle. Where it will not, it meets the normal program's red: the mean wait of a random arrival.
// Both depend on the movement's green share, so a left turn on a short protected phase costs more
// than the through movement beside it.
#pragma once

#include <unordered_map>
#include <vector>

#include "maps/road_graph.hpp"
#include "maps/signal_plan.hpp"
#include "planner/cost_overlay.hpp"

namespace corridor::preemption {

// E[Trans] for an arrival at a uniformly random moment of the normal cycle, the current phase
// taken as conflicting: in a green step of g s with minimum green m, Trans(u) = max(0, m − u) +
// yellow + all-red; in a clearance interval, what is left of it.
double expected_transition_s(const maps::SignalPlan& plan);
// The same for one movement: an arrival while the program already shows it green waits nothing
// (the controller holds that green), and neither does one in a clearance between two steps that
// both serve it. A movement served longer costs less.
double expected_transition_s(const maps::SignalPlan& plan, std::size_t movement);

// The mean red wait of a random arrival for one movement: Σ r² / (2C) over its red runs r in a
// cycle of C s ((C − G)² / (2C), Webster's uniform-arrival term, for one green per cycle). A
// movement the program never serves waits a whole cycle.
double expected_red_delay_s(const maps::SignalPlan& plan, std::size_t movement);
// Its mean over the plan's movements.
double expected_red_delay_s(const maps::SignalPlan& plan);

enum class SignalCostRule {
  preempted,  // the mission's lights are preempted: expected_transition_s
  normal,     // the lights run their program: expected_red_delay_s
};

// Sets, for every plan, the delay of each movement through its node on the overlay, by the rule:
// every pair of an in-edge and an out-edge there gets the value of the plan movement it makes
// (plan_movement), and the node's own delay is 0. A pair the plan has no movement for (no
// movement from that approach) gets the node-wide value.
void set_signal_costs(planner::CostOverlay& overlay, const maps::RoadGraph& graph,
                      const std::unordered_map<NodeId, maps::SignalPlan>& plans, SignalCostRule rule);

}  // namespace corridor::preemption
