// Watches every light change of every intersection and records each breach of the safety rules:
// conflicting movements never both green or yellow; green ends only through yellow of at least the
// plan's yellow time; a movement turns green only after every conflicting one has been red for the
// plan's all-red time; green lasts at least the minimum green.
#pragma once

#include <string>
#include <unordered_map>
#include <vector>

#include "maps/signal_plan.hpp"
#include "preemption/signal_controller.hpp"

namespace corridor::preemption {

class SafetyMonitor {
 public:
  void watch(const maps::SignalPlan& plan, const std::vector<Light>& initial, double now_s);
  void observe(NodeId node, const std::vector<Light>& lights, double time_s);

  [[nodiscard]] const std::vector<std::string>& violations() const { return violations_; }
  [[nodiscard]] std::size_t changes_observed() const { return changes_; }

 private:
  struct Track {
    const maps::SignalPlan* plan;
    std::vector<Light> lights;
    std::vector<double> since_s;  // when each movement took its current light
    double min_green_s;
  };
  void fail(NodeId node, double t, const std::string& what);

  std::unordered_map<NodeId, Track> tracks_;
  std::vector<std::string> violations_;
  std::size_t changes_ = 0;
};

}  // namespace corridor::preemption
