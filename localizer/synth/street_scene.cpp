#include "localizer/synth/street_scene.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <unordered_map>

namespace corridor::localizer::synth {
namespace {

constexpr double kSpacing = 0.5;

// Hash grid over the centre line, so that "is this point too close to the road?" stays cheap.
class ClearanceIndex {
 public:
  explicit ClearanceIndex(const std::vector<maps::Point2>& line) : line_(line) {
    for (std::size_t i = 0; i < line.size(); ++i) cells_[key(line[i])].push_back(i);
  }
  [[nodiscard]] double distance_to_line(maps::Point2 p) const {
    double best = kCell * 2;
    const auto [cx, cy] = cell(p);
    for (int dx = -1; dx <= 1; ++dx) {
      for (int dy = -1; dy <= 1; ++dy) {
        const auto it = cells_.find(pack(cx + dx, cy + dy));
        if (it == cells_.end()) continue;
        for (const std::size_t i : it->second) best = std::min(best, maps::distance_m(p, line_[i]));
      }
    }
    return best;
  }

 private:
  static constexpr double kCell = 16.0;
  static std::pair<long, long> cell(maps::Point2 p) {
    return {static_cast<long>(std::floor(p.x_m / kCell)), static_cast<long>(std::floor(p.y_m / kCell))};
  }
  static long long pack(long x, long y) { return (static_cast<long long>(x) << 32) ^ (y & 0xffffffffLL); }
  static long long key(maps::Point2 p) {
    const auto [x, y] = cell(p);
    return pack(x, y);
  }
  const std::vector<maps::Point2>& line_;
  std::unordered_map<long long, std::vector<std::size_t>> cells_;
};

maps::Point2 normal_left(const std::vector<maps::Point2>& line, std::size_t i) {
  const auto& a = line[i == 0 ? 0 : i - 1];
  const auto& b = line[std::min(i + 1, line.size() - 1)];
  const double dx = b.x_m - a.x_m, dy = b.y_m - a.y_m;
  const double len = std::max(std::hypot(dx, dy), 1e-9);
  return {-dy / len, dx / len};
}

double sun_shade(maps::Point2 a, maps::Point2 b, maps::Point2 toward_viewer) {
  // Normal facing the viewer's side, lit by a sun from the south-west, high in the sky.
  double nx = -(b.y_m - a.y_m), ny = b.x_m - a.x_m;
  const double len = std::max(std::hypot(nx, ny), 1e-9);
  nx /= len;
  ny /= len;
  if (nx * toward_viewer.x_m + ny * toward_viewer.y_m < 0) {
    nx = -nx;
    ny = -ny;
  }
  const double sx = -0.6, sy = -0.8;
  return 0.62 + 0.38 * std::max(0.0, nx * sx + ny * sy);
}

void add_box(std::vector<Wall>& out, maps::Point2 centre, maps::Point2 along, double length, double width,
             double height, int texture) {
  const maps::Point2 side{-along.y_m, along.x_m};
  maps::Point2 c[4];
  const double hl = length / 2, hw = width / 2;
  const double sl[4] = {hl, hl, -hl, -hl}, sw[4] = {hw, -hw, -hw, hw};
  for (int k = 0; k < 4; ++k) {
    c[k] = {centre.x_m + sl[k] * along.x_m + sw[k] * side.x_m, centre.y_m + sl[k] * along.y_m + sw[k] * side.y_m};
  }
  for (int k = 0; k < 4; ++k) {
    const maps::Point2 a = c[k], b = c[(k + 1) % 4];
    const maps::Point2 mid{(a.x_m + b.x_m) / 2, (a.y_m + b.y_m) / 2};
    const maps::Point2 out_dir{mid.x_m - centre.x_m, mid.y_m - centre.y_m};
    out.push_back({a, b, height, 3.1 * k, texture, sun_shade(a, b, out_dir)});
  }
}

}  // namespace

StreetScene build_street_scene(const std::vector<maps::Point2>& line, const SceneOptions& o) {
  StreetScene scene;
  scene.centre_line = line;
  std::mt19937_64 rng(o.seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  auto uniform = [&](double a, double b) { return a + (b - a) * unit(rng); };
  const ClearanceIndex clearance(line);
  const std::size_t n = line.size();

  // Façades: blocks of 12-40 m on each side, set back 6-10 m, with alleys between them. A façade
  // piece that comes closer to the road than its block's setback (the inside of a bend, or where
  // the route passes again) is left out rather than built across the road.
  for (const double side : {1.0, -1.0}) {
    std::size_t i = 0;
    while (i + 2 < n) {
      const std::size_t block = static_cast<std::size_t>(uniform(12.0, 40.0) / kSpacing);
      const double setback = uniform(o.min_setback_m, o.max_setback_m);
      const double height = uniform(7.0, 24.0);
      const int texture = static_cast<int>(uniform(0.0, 4.0));
      double u = uniform(0.0, 50.0);
      const std::size_t end = std::min(n - 1, i + block);
      constexpr std::size_t kPiece = 8;  // 4 m pieces follow curves
      for (std::size_t j = i; j < end; j += kPiece) {
        const std::size_t k = std::min(end, j + kPiece);
        const auto na = normal_left(line, j), nb = normal_left(line, k);
        const maps::Point2 a{line[j].x_m + side * setback * na.x_m, line[j].y_m + side * setback * na.y_m};
        const maps::Point2 b{line[k].x_m + side * setback * nb.x_m, line[k].y_m + side * setback * nb.y_m};
        const maps::Point2 mid{(a.x_m + b.x_m) / 2, (a.y_m + b.y_m) / 2};
        const double len = maps::distance_m(a, b);
        const double min_clear = 0.85 * setback;
        if (len > 0.2 && clearance.distance_to_line(a) > min_clear && clearance.distance_to_line(b) > min_clear &&
            clearance.distance_to_line(mid) > min_clear) {
          const maps::Point2 viewer{line[j].x_m - a.x_m, line[j].y_m - a.y_m};
          scene.walls.push_back({a, b, height, u, texture, sun_shade(a, b, viewer)});
        }
        u += len;
      }
      i = end + static_cast<std::size_t>(uniform(0.0, 10.0) / kSpacing);
    }
  }

  // Kerb-side clutter: poles and parked cars on the right-hand kerb, the odd one on the left.
  for (std::size_t i = 10; i + 10 < n;) {
    const double side = unit(rng) < 0.7 ? -1.0 : 1.0;
    const auto nl = normal_left(line, i);
    const maps::Point2 along{nl.y_m, -nl.x_m};
    const bool car = unit(rng) < 0.5;
    const double lateral = car ? uniform(3.6, 4.4) : uniform(4.6, 5.4);
    const maps::Point2 c{line[i].x_m + side * lateral * nl.x_m, line[i].y_m + side * lateral * nl.y_m};
    if (clearance.distance_to_line(c) > lateral - 0.3) {
      if (car) {
        add_box(scene.walls, c, along, 4.4, 1.8, 1.5, 4);
      } else {
        add_box(scene.walls, c, along, 0.25, 0.25, uniform(3.0, 5.0), 4);
      }
    }
    i += static_cast<std::size_t>(uniform(8.0, 30.0) / kSpacing);
  }

  // Oncoming cars in the left lane; each is visible for a while and then gone.
  const double length_m = (n - 1) * kSpacing;
  const int cars = static_cast<int>(std::round(o.cars_per_km * length_m / 1000.0));
  for (int c = 0; c < cars; ++c) {
    MovingCar car;
    car.speed_mps = uniform(6.0, 12.0);
    car.lateral_m = uniform(2.8, 3.4);
    car.start_time_s = uniform(0.0, std::max(1.0, o.drive_duration_s - 10.0));
    car.end_time_s = car.start_time_s + uniform(8.0, 20.0);
    car.start_arc_m = uniform(0.0, length_m);
    scene.cars.push_back(car);
  }
  return scene;
}

std::vector<Wall> StreetScene::walls_at(double t) const {
  std::vector<Wall> out = walls;
  const double length_m = (centre_line.size() - 1) * kSpacing;
  for (const MovingCar& car : cars) {
    if (t < car.start_time_s || t > car.end_time_s) continue;
    const double s = car.start_arc_m - car.speed_mps * (t - car.start_time_s);
    if (s < 0 || s > length_m) continue;
    const std::size_t i = static_cast<std::size_t>(s / kSpacing);
    const auto nl = normal_left(centre_line, i);
    const maps::Point2 c{centre_line[i].x_m + car.lateral_m * nl.x_m, centre_line[i].y_m + car.lateral_m * nl.y_m};
    add_box(out, c, {nl.y_m, -nl.x_m}, 4.4, 1.8, 1.5, 5);
  }
  return out;
}

}  // namespace corridor::localizer::synth
