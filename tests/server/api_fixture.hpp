// The grid and the tokens the Router tests share: one 8×8 two-way grid with signals, and one
// token per role (each test's rig chooses which to accept).
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "maps/synthetic_grid.hpp"
#include "server/auth.hpp"

namespace corridor::server::testing {

inline const maps::RoadGraph& api_grid() {
  static const maps::RoadGraph g = [] {
    maps::GridSpec spec;
    spec.rows = 8;
    spec.cols = 8;
    spec.seed = 4;
    spec.oneway_fraction = 0.0;
    spec.signal_fraction = 0.5;
    return maps::make_perturbed_grid(spec);
  }();
  return g;
}

inline const std::string kDispatcher = "Bearer dispatcher-token-0123456789";
inline const std::string kViewer = "Bearer viewer-token-0123456789abc";
inline const std::string kSensor = "Bearer sensor-token-0123456789abc";
inline const std::string kAmb1 = "Bearer vehicle-amb1-token-0123456";

inline TokenAuth api_auth() {
  TokenAuth auth;
  auth.add_from_config(nlohmann::json::parse(R"({"tokens":[
    {"token":"dispatcher-token-0123456789","name":"dispatch","roles":["dispatcher"]},
    {"token":"viewer-token-0123456789abc","name":"wall","roles":["viewer"]},
    {"token":"sensor-token-0123456789abc","name":"loops","roles":["sensor"]},
    {"token":"vehicle-amb1-token-0123456","name":"amb1","roles":["vehicle"],"vehicle_id":"amb-1"}]})"));
  return auth;
}

}  // namespace corridor::server::testing
