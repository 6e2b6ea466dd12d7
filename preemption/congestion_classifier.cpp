#include "preemption/congestion_classifier.hpp"

namespace corridor::preemption {

CongestionLevel classify_congestion(const ApproachMeasurement& m, const CongestionClassifierConfig& c) {
  if (m.queue_veh) return *m.queue_veh >= c.queue_high_veh ? CongestionLevel::high : CongestionLevel::low;
  if (m.occupancy) return *m.occupancy >= c.occupancy_high ? CongestionLevel::high : CongestionLevel::low;
  if (m.speed_ratio) return *m.speed_ratio <= c.speed_ratio_high ? CongestionLevel::high : CongestionLevel::low;
  return CongestionLevel::low;
}

}  // namespace corridor::preemption
