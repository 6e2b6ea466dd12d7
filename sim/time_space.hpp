// One run's time–space diagram: each EV's distance along the path it drove against time, and the
// light its movement showed at every signal it crossed, as CSV for any plotting tool and as a
// standalone SVG (signals as horizontal bars coloured by the light, the EV as a line).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace corridor::sim {

struct TimeSpaceSignal {
  std::string tls;
  double distance_m = 0.0;  // where the EV crossed its stop line, along the EV's driven path
  // (time, light) samples of the EV's movement: 'G' green, 'y' yellow, 'r' red.
  std::vector<std::pair<double, char>> states;
  bool preempted = false;  // Corridor held it for this EV
};

struct TimeSpaceTrack {
  std::string ev;
  std::vector<double> t_s;
  std::vector<double> distance_m;
  std::vector<double> speed_mps;
  std::vector<TimeSpaceSignal> signals;
};

// <stem>.ev_trajectory.csv (ev,t_s,distance_m,speed_mps), <stem>.ev_signals.csv
// (ev,tls,distance_m,preempted,t_s,state) and <stem>.time_space.svg. Throws SimError when a file
// cannot be written.
void write_time_space(const std::filesystem::path& stem, const std::vector<TimeSpaceTrack>& tracks,
                      const std::string& title);

// The SVG alone; deterministic for the same data.
std::string render_time_space_svg(const std::vector<TimeSpaceTrack>& tracks, const std::string& title);

}  // namespace corridor::sim
