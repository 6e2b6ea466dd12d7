// Reads SUMO's tripinfo output: per vehicle its travel time, time loss, waiting and stops.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace corridor::sim {

struct TripInfo {
  std::string id;
  std::string vtype;
  double depart_s = 0.0;
  double arrival_s = -1.0;  // -1 when the vehicle had not arrived when the run ended
  double duration_s = 0.0;
  double time_loss_s = 0.0;
  double waiting_time_s = 0.0;
  int waiting_count = 0;  // stops
};

// Throws SimError for a missing or malformed file.
std::vector<TripInfo> read_tripinfo(const std::filesystem::path& file);

}  // namespace corridor::sim
