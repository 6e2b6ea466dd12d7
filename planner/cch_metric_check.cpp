// What a CchMetric can say about itself: whether a witness is a triangle of the arc, the first arc
// whose weight its witness does not give (the tests' invariant), and its memory.
#include <string>

#include "planner/cch_lower_triangles.hpp"

namespace corridor::planner {

bool CchMetric::is_triangle(std::uint32_t arc, Witness w) const {
  const CchTopology& t = *topology_;
  const std::uint32_t n = t.arc_count();
  return w.to_tail < n && w.to_head < n && t.tail(w.to_tail) == t.tail(w.to_head) &&
         t.head(w.to_tail) == t.tail(arc) && t.head(w.to_head) == t.head(arc);
}

std::string CchMetric::invariant_violation() const {
  const CchTopology& t = *topology_;
  for (std::uint32_t arc = 0; arc < t.arc_count(); ++arc) {
    for (const bool upward : {true, false}) {
      const std::uint32_t input = upward ? t.input(arc).up : t.input(arc).down;
      const double today = input == kNoCchArc ? kInfCost : input_s(input);
      if (input_cost(arc, upward) != today) {
        return "arc " + std::to_string(arc) + (upward ? " up" : " down") + " keeps input cost " +
               std::to_string(input_cost(arc, upward)) + " but the turn costs " + std::to_string(today) + " today";
      }
    }
    // The searches' copies of the weights are the metric's own (set_weight writes both).
    if (up_[arc] != way(arc, true).weight || down_[arc] != way(arc, false).weight) {
      return "arc " + std::to_string(arc) + "'s weights for the searches differ from the metric's";
    }
    const double up = derive(arc, true).weight, down = derive(arc, false).weight;
    if (options_.lazy_rises) {
      // Lower bounds: at or below what the triangles and the input give; witnesses may have risen.
      if (up_s(arc) > up || down_s(arc) > down) {
        return "arc " + std::to_string(arc) + " holds " + std::to_string(up_s(arc)) + "/" + std::to_string(down_s(arc)) +
               " above what its triangles give, " + std::to_string(up) + "/" + std::to_string(down);
      }
      // The rival bounds every other way: the input where the witness is a triangle, and every
      // open lower triangle but the witness.
      for (const bool upward : {true, false}) {
        const double rival = lazy(arc, upward).rival;
        const Witness z = witness(arc, upward);
        if (lazy(arc, upward).middle != (z.input() ? kNoCchArc : t.tail(z.to_tail))) {
          return "arc " + std::to_string(arc) + (upward ? " up" : " down") + " keeps a middle not its witness's";
        }
        double other = z.input() ? kInfCost : input_cost(arc, upward);
        for_each_lower_triangle(arc, upward, [&](double sum, Witness tri) {
          if (tri != z) other = std::min(other, sum);
        });
        if (rival > other) {
          return "arc " + std::to_string(arc) + (upward ? " up" : " down") + " has rival bound " +
                 std::to_string(rival) + " above another way's " + std::to_string(other);
        }
      }
      // A weight settle() would take as exact without looking is its witness's sum, over sides
      // it would take as exact too: so, by induction, the cost of the path it unpacks to.
      for (const bool upward : {true, false}) {
        if (!known_exact(arc, upward)) continue;
        const double w = way(arc, upward).weight;
        const Witness z = witness(arc, upward);
        double witnessed = input_cost(arc, upward);
        if (!z.input()) {
          if (!is_triangle(arc, z)) return "arc " + std::to_string(arc) + "'s witness is not a triangle";
          if (!known_exact(z.to_tail, !upward) || !known_exact(z.to_head, upward)) {
            return "arc " + std::to_string(arc) + (upward ? " up" : " down") +
                   " is taken as exact over a side that is not";
          }
          witnessed = side_sum(z, upward);
        }
        if (witnessed != w) {
          return "arc " + std::to_string(arc) + (upward ? " up" : " down") + " is taken as exact at " +
                 std::to_string(w) + " but its witness gives " + std::to_string(witnessed);
        }
      }
      continue;
    }
    if (up != up_s(arc) || down != down_s(arc)) {
      return "arc " + std::to_string(arc) + " holds " + std::to_string(up_s(arc)) + "/" + std::to_string(down_s(arc)) +
             " but its triangles give " + std::to_string(up) + "/" + std::to_string(down);
    }
    // Each finite weight's witness gives exactly it, so unpacking reproduces the weight.
    const CchTopology::Input& in = t.input(arc);
    for (const bool upward : {true, false}) {
      const double w = way(arc, upward).weight;
      if (w >= kInfCost) continue;
      const Witness z = witness(arc, upward);
      const std::uint32_t input = upward ? in.up : in.down;
      double witnessed = kInfCost;
      if (z.input()) {
        if (input != kNoCchArc) witnessed = input_s(input);
      } else if (is_triangle(arc, z)) {
        witnessed = side_sum(z, upward);
      }
      if (witnessed != w) {
        return "arc " + std::to_string(arc) + (upward ? " up" : " down") + " weighs " + std::to_string(w) +
               " but its witness gives " + std::to_string(witnessed);
      }
    }
  }
  return {};
}

std::size_t CchMetric::memory_bytes() const {
  return (up_.size() + down_.size()) * sizeof(double) + ways_.size() * sizeof(Slot) + inputs_.size() * sizeof(Inputs) +
         slot_.size() * sizeof(std::uint32_t) + marks_.size() * sizeof(TreeMark) +
         queue_.memory_bytes() +
         pending_.capacity() * sizeof(Pending) +
         [&] {
           std::size_t bytes = 0;
           for (const OpenLists* l : {&lower_out_, &lower_in_, &upper_out_, &upper_in_}) {
             bytes += l->first.capacity() * sizeof(std::uint32_t) + l->entries.capacity() * sizeof(CchDownArc);
           }
           return bytes + open_.capacity();
         }();
}

}  // namespace corridor::planner
