// Order statistics for experiment summaries.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

namespace corridor::planner {

// The q-quantile with linear interpolation between order statistics (q = 0.5 is the median); NaN
// for no data.
inline double quantile(std::vector<double> v, double q) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  const double pos = q * static_cast<double>(v.size() - 1);
  const auto lo = static_cast<std::size_t>(std::floor(pos));
  const auto hi = static_cast<std::size_t>(std::ceil(pos));
  return v[lo] + (v[hi] - v[lo]) * (pos - static_cast<double>(lo));
}

}  // namespace corridor::planner
