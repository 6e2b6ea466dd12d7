// What a signalized crossing costs a route, by one rule shared by the server and the SUMO loop.
// Where Corridor will preempt the light, the EV meets at most the transition to its green: the
// seed's Trans (remaining minimum green, yellow, all-red), averaged over the normal cycle. Where it
// will not, it meets the normal program's red: the mean wait of a random arrival.
#pragma once

#include <unordered_map>
#include <vector>

#include "maps/signal_plan.hpp"
#include "planner/cost_overlay.hpp"

namespace corridor::preemption {

// E[Trans] for an arrival at a uniformly random moment of the normal cycle, the current phase
// taken as conflicting: in a green step of g s with minimum green m, Trans(u) = max(0, m − u) +
// yellow + all-red; in a clearance interval, what is left of it.
double expected_transition_s(const maps::SignalPlan& plan);

// The mean red wait of a random arrival, over the plan's movements: Σ r² / (2C) over the red runs
// r of each movement in a cycle of C s ((C − G)² / (2C), Webster's uniform-arrival term, for one
// green per cycle). A movement the program never serves waits a whole cycle.
double expected_red_delay_s(const maps::SignalPlan& plan);

enum class SignalCostRule {
  preempted,  // the mission's lights are preempted: expected_transition_s
  normal,     // the lights run their program: expected_red_delay_s
};

// Sets every plan's node delay on the overlay by the rule.
void set_signal_costs(planner::CostOverlay& overlay, const std::unordered_map<NodeId, maps::SignalPlan>& plans,
                      SignalCostRule rule);

}  // namespace corridor::preemption
