#include "maps/signal_map.hpp"

namespace corridor::maps {

SignalMap signal_map_of(std::unordered_map<NodeId, SignalPlan> plans) {
  SignalMap m;
  m.signals = plans;
  m.plans = std::move(plans);
  return m;
}

}  // namespace corridor::maps
