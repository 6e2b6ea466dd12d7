// The 3D street that the synthetic camera sees: building façades lining the road, kerb-side clutter
// (poles, parked cars) and oncoming cars. Every surface is a vertical quad standing on the ground,
// which lets the renderer cast one 2D ray per image column.
#pragma once

#include <cstdint>
#include <vector>

#include "maps/geo.hpp"

namespace corridor::localizer::synth {

struct Wall {
  maps::Point2 a;
  maps::Point2 b;
  double height_m = 10.0;
  double u_offset_m = 0.0;  // texture coordinate at `a`, so neighbouring walls do not repeat
  int texture = 0;          // index into the renderer's façade textures
  double shade = 1.0;       // lighting factor from the wall's orientation to the sun
};

struct MovingCar {
  double start_arc_m = 0.0;  // where along the centre line the car is at t = 0
  double speed_mps = 0.0;    // along decreasing arc: it comes towards the camera
  double lateral_m = 0.0;    // offset to the left of the centre line
  double start_time_s = 0.0;
  double end_time_s = 0.0;
};

struct SceneOptions {
  std::uint64_t seed = 1;
  double min_setback_m = 6.0;  // façade distance from the centre line
  double max_setback_m = 10.0;
  double cars_per_km = 5.0;    // oncoming traffic
  double drive_duration_s = 0.0;
};

struct StreetScene {
  std::vector<maps::Point2> centre_line;  // 0.5 m spacing
  std::vector<Wall> walls;
  std::vector<MovingCar> cars;

  // The static walls plus the cars' box sides at time t.
  [[nodiscard]] std::vector<Wall> walls_at(double time_s) const;
};

StreetScene build_street_scene(const std::vector<maps::Point2>& centre_line, const SceneOptions& options);

}  // namespace corridor::localizer::synth
