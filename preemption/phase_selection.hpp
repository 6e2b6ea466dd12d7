// Which phase to give an emergency vehicle at a signal: the seed paper's rule, generalized to any
// plan. High congestion: every movement of the vehicle's approach. Low congestion: keep the current
// phase if it serves the vehicle, else the serving phase that best serves the other approaches.
#pragma once

#include <optional>
#include <span>
#include <string>
#include <vector>

#include "maps/signal_plan.hpp"

namespace corridor::preemption {

enum class CongestionLevel { low, high };

struct PhaseDecision {
  maps::Phase phase;              // what to show
  std::optional<std::size_t> index;  // its index in the plan, unless synthesized
  bool extend = false;            // the current phase already is the choice
};

// `demand` holds per-movement measured demand (vehicles or veh/h; NaN where a detector reports
// nothing); empty when there are no detectors, and then through and right movements count 2,
// lefts 1. Ties go to the earlier phase in plan order, so the decision is deterministic. Where no
// phase of the plan serves the movement, a phase is synthesized: the vehicle's movement and as many
// of its approach's movements as are mutually compatible, everything else red. `also` are further
// movements the phase must serve with it (a light over several joined junctions that the vehicle
// crosses one after the other).
PhaseDecision select_phase(const maps::SignalPlan& plan, std::size_t movement,
                           std::optional<std::size_t> current_phase, CongestionLevel level,
                           std::span<const double> demand = {}, std::span<const std::size_t> also = {});

// The seed paper's two 12 × 8 tables for the NEMA plan: rows are movements (plan order), columns
// the eight phases as the current phase, cells the chosen phase's label.
struct DecisionTables {
  std::vector<std::string> movements;
  std::vector<std::string> phases;
  std::vector<std::vector<std::string>> high;
  std::vector<std::vector<std::string>> low;
};

DecisionTables nema_decision_tables();

}  // namespace corridor::preemption
