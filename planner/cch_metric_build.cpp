// A CchMetric's construction: the full (basic) customization of every arc from the cost model's
// weights, and the open lists that the incremental repairs walk afterwards.
#include <limits>
#include <stdexcept>

#include "planner/cch_metric.hpp"

namespace corridor::planner {

CchMetric::CchMetric(const CchTopology& topology, const TravelCost& cost, CchMetricOptions options)
    : topology_(&topology),
      cost_(&cost),
      options_(options),
      up_(topology.arc_count()),
      down_(topology.arc_count()),
      ways_(std::size_t{topology.arc_count()} << (options.lazy_rises ? 2 : 1)),
      lazy_shift_(options.lazy_rises ? 1 : 0),
      slot_(topology.arc_count(), 0),
      queue_(topology.arc_count()) {
  if (options_.lazy_rises) {
    inputs_.resize(topology.arc_count());
    // Every weight of the full customization below is exact: found so in batch 1, before any
    // change (and no subtree has seen a rise since).
    for (std::uint32_t arc = 0; arc < topology.arc_count(); ++arc) {
      for (const bool upward : {true, false}) {
        ways_[place_of(arc, upward) + 1].lazy = LazyWay{batch_, kNoCchArc, std::numeric_limits<float>::infinity(), 0};
      }
    }
  }
  if (&topology.turns() != &cost.graph().turns()) {
    throw std::invalid_argument("the contraction hierarchy was built for another graph than the cost model's");
  }
  open_ = open_inputs();
  customize_all(open_);
  for (std::uint32_t arc = 0; arc < topology.arc_count(); ++arc) {
    up_[arc] = way(arc, true).weight;
    down_[arc] = way(arc, false).weight;
  }
  build_open_lists();
  if (options_.lazy_rises) {
    marks_.resize(topology.vertex_count());
    for (std::uint32_t r = 0; r < topology.vertex_count(); ++r) marks_[r] = {batch_, topology.parent(r)};
  }
}

void CchMetric::customize_all(HugePageVector<std::uint8_t>& open) {
  const CchTopology& t = *topology_;
  for (std::uint32_t arc = 0; arc < t.arc_count(); ++arc) {
    const CchTopology::Input& in = t.input(arc);
    way(arc, true).weight = in.up == kNoCchArc ? kInfCost : input_s(in.up);
    way(arc, false).weight = in.down == kNoCchArc ? kInfCost : input_s(in.down);
    if (options_.lazy_rises) inputs_[arc] = {way(arc, true).weight, way(arc, false).weight};
  }
  // Basic customization: every lower triangle {x, a, b} (x lowest) offers a→x→b and b→x→a. Going
  // up by x, an arc's weight is final before any arc above it reads it. The same sweep opens a→b
  // where a→x and x→b are open, whatever they weigh today.
  for (std::uint32_t x = 0; x < t.vertex_count(); ++x) {
    const auto ups = t.up(x);
    const std::uint32_t base = t.first_up(x);
    for (std::size_t i = 0; i < ups.size(); ++i) {
      const std::uint32_t xa = base + static_cast<std::uint32_t>(i);
      if (open[xa] == 0) continue;
      const double a_to_x = way(xa, false).weight;
      const double x_to_a = way(xa, true).weight;
      const bool a_to_x_open = (open[xa] & kDown) != 0, x_to_a_open = (open[xa] & kUp) != 0;
      // The higher neighbours of x above a are higher neighbours of a too (chordality): walk both
      // ascending lists together to find the arcs {a, b}.
      const auto a_ups = t.up(ups[i]);
      std::size_t k = 0;
      for (std::size_t j = i + 1; j < ups.size(); ++j) {
        while (a_ups[k] < ups[j]) ++k;
        const std::uint32_t ab = t.first_up(ups[i]) + static_cast<std::uint32_t>(k);
        const std::uint32_t xb = base + static_cast<std::uint32_t>(j);
        if (a_to_x_open && (open[xb] & kUp) != 0) open[ab] |= kUp;    // a→x→b
        if (x_to_a_open && (open[xb] & kDown) != 0) open[ab] |= kDown;  // b→x→a
        const double up = add_cost(a_to_x, way(xb, true).weight);
        const double down = add_cost(way(xb, false).weight, x_to_a);
        // A lazy metric keeps the best of the ways that lost (lower_rival).
        if (up < way(ab, true).weight) {
          if (options_.lazy_rises) lower_rival(ab, true, way(ab, true).weight);
          way(ab, true).weight = up;
          set_witness(ab, true, Witness{xa, xb}, x);
        } else if (options_.lazy_rises) {
          lower_rival(ab, true, up);
        }
        if (down < way(ab, false).weight) {
          if (options_.lazy_rises) lower_rival(ab, false, way(ab, false).weight);
          way(ab, false).weight = down;
          set_witness(ab, false, Witness{xa, xb}, x);
        } else if (options_.lazy_rises) {
          lower_rival(ab, false, down);
        }
      }
    }
  }
}

HugePageVector<std::uint8_t> CchMetric::open_inputs() const {
  const CchTopology& t = *topology_;
  // An input direction is open unless the profile closes it for good: a restriction or U-turn
  // rule (turn_s), or an edge the vehicle does not fit. The overlay is not read.
  const auto input_open = [&](std::uint32_t index) {
    if (index == kNoCchArc) return false;
    const maps::TurnArc& a = t.turn_arc(index);
    return cost_->turn_s(a) < kInfCost && !cost_->blocked(t.turns().edge_of(a.other));
  };
  HugePageVector<std::uint8_t> open(t.arc_count(), 0);
  for (std::uint32_t arc = 0; arc < t.arc_count(); ++arc) {
    const CchTopology::Input& in = t.input(arc);
    open[arc] = static_cast<std::uint8_t>((input_open(in.up) ? kUp : 0) | (input_open(in.down) ? kDown : 0));
  }
  return open;
}

void CchMetric::build_open_lists() {
  const CchTopology& t = *topology_;
  const HugePageVector<std::uint8_t>& open = open_;
  // The four neighbour lists, by counting. Arc ids ascend by tail and, within a tail, by head, so
  // filling in id order keeps every list ascending.
  const std::size_t n = t.vertex_count();
  for (OpenLists* l : {&lower_out_, &lower_in_, &upper_out_, &upper_in_}) l->first.assign(n + 2, 0);
  for (std::uint32_t arc = 0; arc < t.arc_count(); ++arc) {
    const std::uint32_t x = t.tail(arc), y = t.head(arc);
    if ((open[arc] & kUp) != 0) {  // x→y
      ++lower_in_.first[y + 2];
      ++upper_out_.first[x + 2];
    }
    if ((open[arc] & kDown) != 0) {  // y→x
      ++lower_out_.first[y + 2];
      ++upper_in_.first[x + 2];
    }
  }
  for (OpenLists* l : {&lower_out_, &lower_in_, &upper_out_, &upper_in_}) {
    for (std::size_t r = 2; r < l->first.size(); ++r) l->first[r] += l->first[r - 1];
    l->entries.resize(l->first.back());
  }
  // first[r + 1] is the next free slot of r's list while filling; afterwards first[r] begins it.
  const auto put = [](OpenLists& l, std::uint32_t r, std::uint32_t neighbour, std::uint32_t arc) {
    l.entries[l.first[r + 1]++] = CchDownArc{neighbour, arc};
  };
  for (std::uint32_t arc = 0; arc < t.arc_count(); ++arc) {
    const std::uint32_t x = t.tail(arc), y = t.head(arc);
    if ((open[arc] & kUp) != 0) {
      put(lower_in_, y, x, arc);
      put(upper_out_, x, y, arc);
    }
    if ((open[arc] & kDown) != 0) {
      put(lower_out_, y, x, arc);
      put(upper_in_, x, y, arc);
    }
  }
  for (OpenLists* l : {&lower_out_, &lower_in_, &upper_out_, &upper_in_}) l->first.pop_back();
}

}  // namespace corridor::planner
