// Signal plans: an intersection's movements, which of them conflict, the phases that may be shown,
// and the normal program that cycles through them. Read by preemption and by the SUMO bridge.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "maps/geo.hpp"
#include "maps/ids.hpp"

namespace corridor::maps {

enum class Compass : std::uint8_t { north, east, south, west };
enum class Turn : std::uint8_t { through, right, left };

char compass_letter(Compass c);

// The compass sector (90° wide, centred on N, E, S, W) of `toward` seen from `center`, in a frame
// whose y axis points north.
Compass compass_side(Point2 center, Point2 toward);

struct Movement {
  Compass from = Compass::north;  // the approach the traffic comes from
  Compass to = Compass::south;    // the leg it leaves by
  Turn turn = Turn::through;
  std::uint8_t nema = 0;  // NEMA movement number 1..8, 0 when the plan is not NEMA

  [[nodiscard]] std::string label() const;  // "N->S"
};

// Which movements a phase shows green. All others are red.
struct Phase {
  std::string label;  // "4+7" for NEMA plans
  std::vector<std::uint8_t> green;  // per movement, 1 = green
  double min_green_s = 5.0;

  [[nodiscard]] bool serves(std::size_t movement) const { return green[movement] != 0; }
};

struct ProgramStep {
  std::size_t phase = 0;
  double green_s = 20.0;
};

struct SignalPlan {
  NodeId node;
  std::vector<Movement> movements;
  std::vector<std::uint8_t> conflict;  // movements × movements, 1 = may not be green together
  std::vector<Phase> phases;           // every phase the controller may show
  std::vector<ProgramStep> program;    // the normal cycle, in order
  double yellow_s = 3.0;
  double all_red_s = 2.0;
  // Optional, per movement: the graph edge a vehicle takes when it makes that movement (SUMO
  // plans, where a movement is one link). Where set it identifies movements exactly; otherwise
  // they are matched by compass sides.
  std::vector<EdgeId> movement_edge;
  // Optional, per movement: the other movements whose vehicles queue in the same lane (SUMO plans,
  // from the links' lanes). A vehicle making one waits behind the first vehicle making another, so
  // a hold for one shows them all green, or the vehicle stands behind a red it does not take.
  std::vector<std::vector<std::size_t>> lane_mates;

  [[nodiscard]] bool conflicts(std::size_t a, std::size_t b) const { return conflict[a * movements.size() + b] != 0; }
  [[nodiscard]] std::optional<std::size_t> movement_index(Compass from, Compass to) const;
  [[nodiscard]] std::optional<std::size_t> phase_index(const std::string& label) const;
  [[nodiscard]] double cycle_s() const;
  // True when no two movements that a phase shows green conflict.
  [[nodiscard]] bool phase_is_safe(const Phase& phase) const;
};

struct NemaTiming {
  double left_green_s = 10.0;
  double through_green_s = 25.0;
  double min_green_s = 5.0;
  double yellow_s = 3.0;
  double all_red_s = 2.0;
  // Optional, per movement: the graph edge a vehicle takes when it makes that movement (SUMO
  // plans, where a movement is one link). Where set it identifies movements exactly; otherwise
  // they are matched by compass sides.
  std::vector<EdgeId> movement_edge;
};

// The NEMA dual-ring 8-phase plan of the seed paper (and Kim & Kwon): movements 4/7 from North,
// 8/3 from South, 2/5 from West, 6/1 from East (through-and-right / left), phases the compatible
// pairs 1+5, 1+6, 2+5, 2+6, 3+7, 3+8, 4+7, 4+8, and a normal cycle 4+7, 4+8, 3+8, 2+5, 2+6, 1+6.
// `legs` says which of N, E, S, W exist (bit per Compass value): a missing leg drops its movements
// and the movements into it, and program steps left with nothing green.
SignalPlan make_nema_plan(NodeId node, std::uint8_t legs = 0b1111, const NemaTiming& timing = {});

// The NEMA movement number for traffic from `from` turning `turn` (right-hand traffic).
std::uint8_t nema_movement(Compass from, Turn turn);

}  // namespace corridor::maps
