// Finding the next place in an ascending list, starting from where the last search ended: the
// walks of a contraction hierarchy (planner/cch_metric.cpp, planner/cch_search_space.cpp) go
// through one list along the ascending entries of another, and the two interleave closely in
// some places and run far apart in others (a high vertex's lists hold thousands).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>

namespace corridor::planner {

// The first element at or after `it` whose key(element) is not below `r`: a few steps one by one,
// then galloping (doubling steps) and a binary search of the last step.
template <typename It, typename Key>
It gallop_to(It it, It end, std::uint32_t r, Key key) {
  for (int n = 0; n < 4; ++n) {
    if (it == end || key(*it) >= r) return it;
    ++it;
  }
  std::ptrdiff_t step = 1;
  while (step < end - it && key(it[step]) < r) step *= 2;
  return std::lower_bound(it + step / 2, it + std::min(step + 1, end - it), r,
                          [&](const auto& e, std::uint32_t v) { return key(e) < v; });
}

}  // namespace corridor::planner
