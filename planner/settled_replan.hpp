// D* Lite on a contraction hierarchy whose rises are lazy (CchMetricOptions::lazy_rises): the
// repair runs on lower bounds, so the arcs of the route it finds are settled (made exact); where
// one of them rose, the planner is told and the repair runs again. A route whose cost equals the
// lower bound it was found with is a cheapest one, so the routes stay exact; a replan pays only
// for the rises its routes meet.
#pragma once

#include <cstdint>

#include "planner/dstar_lite.hpp"

namespace corridor::planner {

struct SettledReplan {
  ReplanStats stats;       // summed over the repairs
  Route route;             // the route, its travel time under today's costs
  std::uint32_t repairs = 0;  // D* Lite repairs run: 1 when the first route's cost held
  std::uint64_t settled = 0;  // arcs whose weight settling raised, counted once per round
};

// Replans `planner`, whose hierarchy is `metric`. std::invalid_argument when the planner searches
// another metric, or when a lazy metric is already bound to another planner (a lazy metric serves
// one planner: CchMetric::bind_settler). On an eager metric this is one replan() and route().
SettledReplan replan_settled(CchMetric& metric, CchDStarLite& planner);

}  // namespace corridor::planner
