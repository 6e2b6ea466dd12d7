#include "planner/settled_replan.hpp"

#include <algorithm>
#include <stdexcept>

namespace corridor::planner {

SettledReplan replan_settled(CchMetric& metric, CchDStarLite& planner) {
  if (&planner.space().metric() != &metric) {
    throw std::invalid_argument("replan_settled: the planner searches another hierarchy than the metric given");
  }
  if (metric.lazy_rises() && !metric.bind_settler(&planner)) {
    throw std::invalid_argument("replan_settled: a metric with lazy rises serves one planner, and another settles it");
  }
  SettledReplan out;
  std::vector<std::uint32_t> raised;
  // Settles the hierarchy arcs of `path`; true when one was raised (then reported to the planner).
  const auto settle_path = [&](const std::vector<CchVia>& path) {
    raised.clear();
    for (const CchVia& via : path) {
      planner.space().for_each_hierarchy_arc(via, [&](std::uint32_t arc, bool upward) { (void)metric.settle(arc, upward, raised); });
    }
    if (raised.empty()) return false;
    std::sort(raised.begin(), raised.end());
    raised.erase(std::unique(raised.begin(), raised.end()), raised.end());
    out.settled += raised.size();
    planner.arcs_changed(raised);
    return true;
  };
  // The route along the values from before this batch (a greedy walk from the moved start) is the
  // likeliest to meet its rises (updates gather on main roads): settled first, it costs no repair
  // round of its own.
  if (metric.lazy_rises()) (void)settle_path(planner.path());
  std::vector<CchVia> path;
  for (;;) {
    const ReplanStats s = planner.replan();
    ++out.repairs;
    out.stats.expanded += s.expanded;
    out.stats.rekeyed += s.rekeyed;
    out.stats.underconsistent += s.underconsistent;
    out.stats.updated += s.updated;
    out.stats.path_checks += s.path_checks;
    out.stats.activated += s.activated;
    path = planner.path();
    // A route whose every arc was already exact costs what the planner found on lower bounds: it
    // is a cheapest one. No route on lower bounds is no route at all.
    if (!metric.lazy_rises() || !settle_path(path)) break;
  }
  out.route = planner.space().route_along(path);
  return out;
}

}  // namespace corridor::planner
