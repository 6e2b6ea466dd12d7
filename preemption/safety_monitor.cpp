#include "preemption/safety_monitor.hpp"

#include <algorithm>
#include <sstream>

namespace corridor::preemption {
namespace {
constexpr double kTimeSlack = 1e-9;  // event times are exact sums; allow rounding only
}

void SafetyMonitor::watch(const maps::SignalPlan& plan, const std::vector<Light>& initial, double now_s) {
  double min_green = 1e9;
  for (const auto& p : plan.phases) min_green = std::min(min_green, p.min_green_s);
  // Whatever shows at the start counts as long established.
  tracks_[plan.node] = Track{&plan, initial, std::vector<double>(initial.size(), now_s - 1e6), min_green};
}

void SafetyMonitor::fail(NodeId node, double t, const std::string& what) {
  std::ostringstream msg;
  msg << "node " << node.v << " at " << t << " s: " << what;
  violations_.push_back(msg.str());
}

void SafetyMonitor::observe(NodeId node, const std::vector<Light>& lights, double t) {
  auto it = tracks_.find(node);
  if (it == tracks_.end()) return;
  Track& tr = it->second;
  const maps::SignalPlan& plan = *tr.plan;
  const std::size_t n = lights.size();
  ++changes_;
  for (std::size_t m = 0; m < n; ++m) {
    const Light before = tr.lights[m], after = lights[m];
    if (before == after) continue;
    const double held = t - tr.since_s[m];
    const std::string label = plan.movements[m].label();
    if (before == Light::green && after == Light::red) fail(node, t, label + " went from green to red without yellow");
    if (before == Light::green && after == Light::yellow && held + kTimeSlack < tr.min_green_s) {
      fail(node, t, label + " green lasted " + std::to_string(held) + " s, under the minimum green");
    }
    if (before == Light::yellow && held + kTimeSlack < plan.yellow_s) {
      fail(node, t, label + " yellow lasted " + std::to_string(held) + " s, under the yellow time");
    }
    if (before == Light::yellow && after == Light::green) fail(node, t, label + " went from yellow back to green");
    if (before == Light::red && after == Light::yellow) fail(node, t, label + " went from red to yellow");
    if (after == Light::green) {
      for (std::size_t c = 0; c < n; ++c) {
        if (c == m || !plan.conflicts(m, c)) continue;
        // Compare with the conflicting movement's light before this change.
        if (tr.lights[c] != Light::red) {
          fail(node, t, label + " turned green while conflicting " + plan.movements[c].label() + " was not red");
        } else if (t - tr.since_s[c] + kTimeSlack < plan.all_red_s) {
          fail(node, t, label + " turned green " + std::to_string(t - tr.since_s[c]) + " s after conflicting " +
                            plan.movements[c].label() + " turned red, under the all-red time");
        }
      }
    }
  }
  for (std::size_t m = 0; m < n; ++m) {
    if (tr.lights[m] != lights[m]) {
      tr.lights[m] = lights[m];
      tr.since_s[m] = t;
    }
  }
  for (std::size_t a = 0; a < n; ++a) {
    for (std::size_t b = a + 1; b < n; ++b) {
      if (lights[a] != Light::red && lights[b] != Light::red && plan.conflicts(a, b)) {
        fail(node, t, "conflicting " + plan.movements[a].label() + " and " + plan.movements[b].label() + " both shown");
      }
    }
  }
}

}  // namespace corridor::preemption
