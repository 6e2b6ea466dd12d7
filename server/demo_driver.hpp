// `corridor serve --demo`: simulated ambulances that drive their missions' routes through the same
// service calls a real vehicle's reports take, at the planned speeds with noise, plus occasional
// congestion on a route ahead, so that a newcomer sees a mission come alive without SUMO.
#pragma once

#include <cstdint>
#include <random>
#include <string>
#include <unordered_map>

#include "server/dispatch_service.hpp"

namespace corridor::server {

struct DemoConfig {
  int missions = 3;                  // keeps this many demo missions active
  double speed_noise = 0.15;         // each step's speed is the plan's × (1 ± this), uniformly
  double congestion_period_s = 25.0;  // one congestion report this often, on a demo route ahead
  double congestion_factor = 4.0;
  double congestion_expiry_s = 90.0;
  double min_trip_m = 800.0;  // straight-line distance between a demo mission's ends
  std::uint64_t seed = 1;
  std::string vehicle_prefix = "demo-";
};

class DemoDriver {
 public:
  DemoDriver(DispatchService& service, DemoConfig config);

  // Advances every demo vehicle by dt_s of driving, tops up the demo missions, and now and then
  // reports congestion. Errors from the service (a vehicle that cannot be placed, an unreachable
  // destination) are logged and skipped: the demo never stops the server.
  void step(double now_s, double dt_s);

  [[nodiscard]] std::size_t positions_sent() const { return positions_sent_; }

 private:
  void top_up(double now_s);
  void drive(const MissionView& m, double now_s, double dt_s);
  void congest(double now_s);

  DispatchService& service_;
  DemoConfig config_;
  std::mt19937_64 rng_;
  std::uint64_t next_vehicle_ = 1;
  double next_congestion_s_ = 0;
  std::size_t positions_sent_ = 0;
};

}  // namespace corridor::server
