// Travel-time cost values in seconds, with one named infinity and one saturating add.
#pragma once

#include <cmath>
#include <limits>

namespace corridor::planner {

// Unreachable. IEEE infinity absorbs additions, so sums can neither overflow nor wrap.
inline constexpr double kInfCost = std::numeric_limits<double>::infinity();

// Every cost sum goes through here: NaN (for example 0 × ∞ from a closed edge) becomes kInfCost.
inline double add_cost(double a, double b) {
  const double s = a + b;
  return std::isnan(s) ? kInfCost : s;
}

}  // namespace corridor::planner
