#include "maps/signal_plan.hpp"

#include <array>
#include <cmath>

namespace corridor::maps {
namespace {

constexpr std::array<std::pair<int, int>, 8> kNemaPairs{{{4, 7}, {4, 8}, {3, 8}, {3, 7}, {2, 5}, {2, 6}, {1, 6}, {1, 5}}};
// Indices into kNemaPairs of the normal cycle: 4+7, 4+8, 3+8, 2+5, 2+6, 1+6.
constexpr std::array<std::size_t, 6> kNormalCycle{0, 1, 2, 4, 5, 6};

// Right-hand traffic: coming from `from`, where does each turn leave?
Compass exit_for(Compass from, Turn turn) {
  const int f = static_cast<int>(from);
  switch (turn) {
    case Turn::through: return static_cast<Compass>((f + 2) % 4);
    case Turn::right: return static_cast<Compass>((f + 3) % 4);  // southbound turning right heads west
    case Turn::left: return static_cast<Compass>((f + 1) % 4);   // southbound turning left heads east
  }
  return from;
}

bool nema_compatible(int a, int b) {
  if (a == b) return true;
  for (auto [x, y] : kNemaPairs) {
    if ((x == a && y == b) || (x == b && y == a)) return true;
  }
  return false;
}

}  // namespace

char compass_letter(Compass c) { return "NESW"[static_cast<int>(c)]; }

Compass compass_side(Point2 center, Point2 toward) {
  const double angle = std::atan2(toward.y_m - center.y_m, toward.x_m - center.x_m) * 180.0 / M_PI;
  if (angle >= 45.0 && angle < 135.0) return Compass::north;
  if (angle >= -45.0 && angle < 45.0) return Compass::east;
  if (angle >= -135.0 && angle < -45.0) return Compass::south;
  return Compass::west;
}

std::string Movement::label() const { return std::string{compass_letter(from)} + "->" + compass_letter(to); }

std::uint8_t nema_movement(Compass from, Turn turn) {
  const bool left = turn == Turn::left;
  switch (from) {
    case Compass::north: return left ? 7 : 4;
    case Compass::south: return left ? 3 : 8;
    case Compass::west: return left ? 5 : 2;
    case Compass::east: return left ? 1 : 6;
  }
  return 0;
}

std::optional<std::size_t> SignalPlan::movement_index(Compass from, Compass to) const {
  for (std::size_t i = 0; i < movements.size(); ++i) {
    if (movements[i].from == from && movements[i].to == to) return i;
  }
  return std::nullopt;
}

std::optional<std::size_t> SignalPlan::phase_index(const std::string& label) const {
  for (std::size_t i = 0; i < phases.size(); ++i) {
    if (phases[i].label == label) return i;
  }
  return std::nullopt;
}

double SignalPlan::cycle_s() const {
  double total = 0.0;
  for (const auto& step : program) total += step.green_s + yellow_s + all_red_s;
  return total;
}

bool SignalPlan::phase_is_safe(const Phase& phase) const {
  for (std::size_t a = 0; a < movements.size(); ++a) {
    for (std::size_t b = a + 1; b < movements.size(); ++b) {
      if (phase.serves(a) && phase.serves(b) && conflicts(a, b)) return false;
    }
  }
  return true;
}

SignalPlan make_nema_plan(NodeId node, std::uint8_t legs, const NemaTiming& timing) {
  SignalPlan plan;
  plan.node = node;
  plan.yellow_s = timing.yellow_s;
  plan.all_red_s = timing.all_red_s;
  auto has_leg = [&](Compass c) { return (legs >> static_cast<int>(c) & 1) != 0; };
  // Order: approaches N, S, E, W; for each, through, right, left. This is the tables' row order.
  for (Compass from : {Compass::north, Compass::south, Compass::east, Compass::west}) {
    for (Turn turn : {Turn::through, Turn::right, Turn::left}) {
      const Compass to = exit_for(from, turn);
      if (!has_leg(from) || !has_leg(to)) continue;
      plan.movements.push_back({from, to, turn, nema_movement(from, turn)});
    }
  }
  const std::size_t n = plan.movements.size();
  plan.conflict.assign(n * n, 0);
  for (std::size_t a = 0; a < n; ++a) {
    for (std::size_t b = 0; b < n; ++b) {
      plan.conflict[a * n + b] = nema_compatible(plan.movements[a].nema, plan.movements[b].nema) ? 0 : 1;
    }
  }
  std::vector<std::size_t> kept;  // kNemaPairs index -> plan phase, for phases with any green left
  for (std::size_t p = 0; p < kNemaPairs.size(); ++p) {
    const auto [x, y] = kNemaPairs[p];
    Phase phase;
    phase.label = std::to_string(x) + "+" + std::to_string(y);
    phase.min_green_s = timing.min_green_s;
    phase.green.assign(n, 0);
    bool any = false;
    for (std::size_t m = 0; m < n; ++m) {
      if (plan.movements[m].nema == x || plan.movements[m].nema == y) {
        phase.green[m] = 1;
        any = true;
      }
    }
    kept.push_back(any ? plan.phases.size() : SIZE_MAX);
    if (any) plan.phases.push_back(std::move(phase));
  }
  for (std::size_t p : kNormalCycle) {
    if (kept[p] == SIZE_MAX) continue;
    // Odd NEMA numbers are the left turns: phases with one get the shorter left-turn green.
    const bool has_left = kNemaPairs[p].first % 2 == 1 || kNemaPairs[p].second % 2 == 1;
    plan.program.push_back({kept[p], has_left ? timing.left_green_s : timing.through_green_s});
  }
  return plan;
}

}  // namespace corridor::maps
