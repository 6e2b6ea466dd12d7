// The lower triangles of a hierarchy arc, walked by merging two ascending open lists: the inner loop
// of every derivation, the invariant check and the lazy settle, so it is a template that each of
// them inlines. Private to the CchMetric sources.
#pragma once

#include "planner/cch_metric.hpp"
#include "planner/gallop.hpp"

namespace corridor::planner {
namespace cch_detail {

// A lambda, not a function: gallop_to takes the key by value, and a function pointer there is not
// inlined.
inline constexpr auto tail_of = [](const CchDownArc& d) { return d.tail; };

}  // namespace cch_detail

template <class F>
void CchMetric::for_each_lower_triangle(std::uint32_t arc, bool upward, F&& f) const {
  const CchTopology& t = *topology_;
  const std::uint32_t x = t.tail(arc), y = t.head(arc);
  // Lower triangles {z, x, y}, z below x, open the way asked: x→z→y upward, y→z→x downward.
  // Both lists ascend by z.
  const auto zx = upward ? lower_out_.of(x) : lower_in_.of(x);
  const auto zy = upward ? lower_in_.of(y) : lower_out_.of(y);
  auto i = zx.begin();
  auto j = zy.begin();
  while (i != zx.end() && j != zy.end() && j->tail < x) {
    if (i->tail < j->tail) {
      i = gallop_to(i, zx.end(), j->tail, cch_detail::tail_of);
    } else if (j->tail < i->tail) {
      j = gallop_to(j, zy.end(), i->tail, cch_detail::tail_of);
    } else {
      const Witness z{i->arc, j->arc};
      f(side_sum(z, upward), z);
      ++i;
      ++j;
    }
  }
}

}  // namespace corridor::planner
