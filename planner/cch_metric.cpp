#include "planner/cch_metric.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "planner/cch_lower_triangles.hpp"

namespace corridor::planner {

void CchMetric::mark_changed(std::uint32_t arc) {
  if (!options_.lazy_rises || arc == kNoCchArc) return;
  // The arc's lower end and its ancestors: every subtree that holds this input. A vertex already
  // marked in this batch has its ancestors marked too.
  for (std::uint32_t r = topology_->tail(arc); r != kNoCchArc && marks_[r].changed_below != batch_; r = marks_[r].parent) {
    marks_[r].changed_below = batch_;
  }
}

void CchMetric::lower_rival(std::uint32_t arc, bool upward, double s) {
  float& rival = lazy(arc, upward).rival;
  if (s >= static_cast<double>(rival)) return;
  // The float at or below s: a bound rounded up could hide a cheaper way.
  float f = static_cast<float>(s);
  if (static_cast<double>(f) > s) f = std::nextafter(f, -std::numeric_limits<float>::infinity());
  rival = f;
}

double CchMetric::input_s(std::uint32_t index) const {
  const maps::TurnGraph& turns = topology_->turns();
  const maps::TurnArc& a = topology_->turn_arc(index);
  const EdgeId in = turns.edge_of(topology_->turn_arc_source(index));
  const EdgeId onto = turns.edge_of(a.other);
  const double turn = cost_->turn_cost_s(in, a, onto);
  return turn >= kInfCost ? kInfCost : add_cost(turn, cost_->transit_s(onto));
}

CchMetric::Derived CchMetric::derive(std::uint32_t arc, bool upward) const {
  Derived d{input_cost(arc, upward), Witness{}};
  for_each_lower_triangle(arc, upward, [&](double w, Witness via) {
    if (w < d.weight) d = Derived{w, via};
  });
  return d;
}

void CchMetric::queue(std::uint32_t arc, std::uint8_t derive) {
  if (arc == kNoCchArc) return;
  if (slot_[arc] != 0) {
    pending_[slot_[arc] - 1].derive |= derive;
    return;
  }
  pending_.push_back({way(arc, true).weight, way(arc, false).weight, derive});
  slot_[arc] = static_cast<std::uint32_t>(pending_.size());
  queue_.push(arc);
}

void CchMetric::prefetch_offer(std::uint32_t arc, bool upward) const {
  __builtin_prefetch(&way(arc, upward), 1);
}

void CchMetric::offer(std::uint32_t arc, bool upward, double old_s, double new_s, Witness via, std::uint32_t middle) {
  const double current = way(arc, upward).weight;
  if (!options_.lazy_rises) {
    if (new_s < current) {
      queue(arc, 0);
      set_weight(arc, upward, new_s);
      set_witness(arc, upward, via, middle);
    } else if (new_s > old_s && old_s == current) {
      // The path through this triangle was (one of) the arc's cheapest and got dearer: only a
      // full look at its triangles tells its new weight.
      queue(arc, upward ? kUp : kDown);
    }
    return;
  }
  const Witness own = witness(arc, upward);
  // The way that loses, this triangle or the witness it replaces, costs at least `current`.
  if (own != via) lower_rival(arc, upward, std::max(new_s, current));
  if (new_s < current) {
    queue(arc, 0);
    set_weight(arc, upward, new_s);
    set_witness(arc, upward, via, middle);
  } else if (new_s < old_s && own == via) {
    // The arc's own witness got cheaper and the weight did not move: the fall vanished in
    // rounding. The path under the weight changed all the same (a side took a new witness), so
    // the arc and every arc above it must be looked at again, as after a rise.
    lazy(arc, upward).exact = 0;
    mark_changed(arc);
  }
}

// A turn u→v is the input of arc {u, v} upward when u ranks below v, downward otherwise.
void CchMetric::queue_turns_into(std::uint32_t v) {
  const CchTopology& t = *topology_;
  for (const maps::TurnArc& a : t.turns().arcs_in(v)) {
    if (a.other == v) continue;
    const std::uint32_t ru = t.rank(a.other), rv = t.rank(v);
    queue(t.find_arc(ru, rv), ru < rv ? kUp : kDown);
  }
}

void CchMetric::queue_turns_out_of(std::uint32_t v) {
  const CchTopology& t = *topology_;
  for (const maps::TurnArc& a : t.turns().arcs_out(v)) {
    if (a.other == v) continue;
    const std::uint32_t rv = t.rank(v), rw = t.rank(a.other);
    queue(t.find_arc(rv, rw), rv < rw ? kUp : kDown);
  }
}

CustomizationStats CchMetric::edges_changed(std::span<const EdgeId> edges, std::vector<std::uint32_t>& changed) {
  // An edge's conditions enter every turn onto it (the turn's input cost drives the edge), and the
  // turns onto its via-way copies.
  ++batch_;
  for (EdgeId e : edges) {
    queue_turns_into(e.v);
    for (std::uint32_t c : topology_->turns().copies_of(e)) queue_turns_into(c);
  }
  return propagate(changed);
}

CustomizationStats CchMetric::nodes_changed(std::span<const NodeId> nodes, std::vector<std::uint32_t>& changed) {
  // A node's delay enters every turn made at it: the turns out of the vertices standing there.
  const maps::RoadGraph& g = cost_->graph();
  ++batch_;
  for (NodeId n : nodes) {
    for (EdgeId e : g.in_edges(n)) {
      queue_turns_out_of(e.v);
      for (std::uint32_t c : topology_->turns().copies_of(e)) queue_turns_out_of(c);
    }
  }
  return propagate(changed);
}

CustomizationStats CchMetric::propagate(std::vector<std::uint32_t>& changed) {
  const CchTopology& t = *topology_;
  CustomizationStats stats;
  // An arc's triangles below it have lower ends below its own, so they are settled before it comes
  // off the queue; the writes to it all come from arcs below it, which are settled before it too.
  while (!queue_.empty()) {
    const std::uint32_t arc = queue_.pop();
    const Pending p = pending_[slot_[arc] - 1];
    slot_[arc] = 0;
    for (const bool upward : {true, false}) {
      if ((p.derive & (upward ? kUp : kDown)) == 0) continue;
      ++stats.recomputed;
      Way& me = way(arc, upward);
      const double w = me.weight;
      if (options_.lazy_rises) {
        // Only a cheaper input can move a lower bound down; a dearer one waits for settle(), and
        // from now on every weight whose path may use it is stale (mark_changed).
        const std::uint32_t input = upward ? t.input(arc).up : t.input(arc).down;
        const double in = input == kNoCchArc ? kInfCost : input_s(input);
        double& kept = upward ? inputs_[arc].up : inputs_[arc].down;
        const bool by_input = lazy(arc, upward).middle == kNoCchArc;  // the witness is the input (set_witness)
        if (in > kept) {
          mark_changed(arc);
          // A weight that is this input's cost is a real path's cost no longer.
          if (by_input) lazy(arc, upward).exact = 0;
        }
        kept = in;
        if (in < w) {
          // The witness that loses stays a way to derive the weight, at or above the weight.
          if (!by_input) lower_rival(arc, upward, w);
          set_weight(arc, upward, in);
          set_witness(arc, upward, Witness{}, kNoCchArc);
        } else if (!by_input) {
          lower_rival(arc, upward, in);
        }
      } else {
        const Derived d = derive(arc, upward);
        set_weight(arc, upward, d.weight);
        me.via = d.via;
      }
    }
    const bool up_moved = way(arc, true).weight != p.old_up;      // x→y
    const bool down_moved = way(arc, false).weight != p.old_down;  // y→x
    if (!up_moved && !down_moved) continue;
    ++stats.changed;
    changed.push_back(arc);
    if (options_.lazy_rises) {
      // A lower bound that a fall moved (down) is not known to be exact: settle() must look. One
      // that did not move is exact still: it lies at or below today's cost, and a fall can only
      // have lowered that cost from the one it was found exact at, which is the weight itself.
      // So a fall marks only the weights it moves, where a rise marks its whole subtree.
      if (up_moved) lazy(arc, true).exact = 0;
      if (down_moved) lazy(arc, false).exact = 0;
    }
    // {x, y} is a lower side of every triangle {x, y, z} with z above x; the triangle's arc
    // between y and z is offered y→x→z (riding on y→x) and z→x→y (riding on x→y). Only open
    // directions x→z and z→x can carry anything.
    const std::uint32_t x = t.tail(arc), y = t.head(arc);
    const auto y_ups = t.up(y);
    const auto y_downs = t.down(y);
    // The arc between y and z (a neighbour of y by chordality), with z ascending: below y, a
    // gallop onwards through y's lower list (long, but it stays in cache across the loop); above
    // y, a walk along its short ascending higher list.
    const auto between = [&](std::uint32_t z, std::size_t& k, std::size_t& m) {
      if (z < y) {
        m = static_cast<std::size_t>(gallop_to(y_downs.begin() + static_cast<std::ptrdiff_t>(m), y_downs.end(), z, cch_detail::tail_of) -
                                     y_downs.begin());
        assert(m < y_downs.size() && y_downs[m].tail == z);
        return y_downs[m].arc;
      }
      while (y_ups[k] < z) ++k;
      return t.first_up(y) + static_cast<std::uint32_t>(k);
    };
    // The triangles riding on one direction of {x, y} that moved: y→x→z (on y→x, through open
    // x→z) `from_y`, z→x→y (on x→y, through open z→x) otherwise.
    // In two passes: the offers read and write arcs scattered over the metric (an arc direction's
    // weight, witness and rival share a line, and a lowered weight is written to the searches'
    // array too), so the arcs are gathered and their lines fetched first, and the misses overlap
    // instead of coming one after another. The offers change only arcs above x, none of x's own,
    // so the sides read in the first pass still hold.
    const auto offer_triangles = [&](bool from_y, double old_s, double new_s) {
      std::size_t k = 0, m = 0;
      offers_.clear();
      for (const CchDownArc& e : from_y ? upper_out_.of(x) : upper_in_.of(x)) {
        const std::uint32_t z = e.tail, xz = e.arc;
        if (z == y) continue;
        // A sibling still queued offers its weights as they were when it was queued: its own turn
        // will offer the step from there to its new weights, so each triangle's sum moves by one
        // chain of steps that starts at the sum the arc above was derived from.
        const Pending* queued = slot_[xz] != 0 ? &pending_[slot_[xz] - 1] : nullptr;
        const double side = from_y ? (queued != nullptr ? queued->old_up : up_[xz])
                                   : (queued != nullptr ? queued->old_down : down_[xz]);
        if (side >= kInfCost) continue;
        const std::uint32_t target = between(z, k, m);
        const bool upward = from_y == (z > y);
        prefetch_offer(target, upward);
        // The arc {y, z}'s witness is x: its sides are {x, y} (this arc) and {x, z}.
        offers_.push_back({target, upward, side, z > y ? Witness{arc, xz} : Witness{xz, arc}});
      }
      for (const Offer& o : offers_) offer(o.arc, o.upward, add_cost(old_s, o.side), add_cost(new_s, o.side), o.via, x);
    };
    if (down_moved) offer_triangles(true, p.old_down, way(arc, false).weight);
    if (up_moved) offer_triangles(false, p.old_up, way(arc, true).weight);
  }
  pending_.clear();
  return stats;
}

void CchMetric::unpack(std::uint32_t arc, bool upward, std::vector<std::uint32_t>& out) const {
  const CchTopology& t = *topology_;
  const Witness w = witness(arc, upward);
  if (w.input()) {
    out.push_back(t.vertex_at(upward ? t.head(arc) : t.tail(arc)));
    return;
  }
  // A shortcut: x→z→y upward, y→z→x downward, z below both.
  if (upward) {
    unpack(w.to_tail, false, out);
    unpack(w.to_head, true, out);
  } else {
    unpack(w.to_head, false, out);
    unpack(w.to_tail, true, out);
  }
}

double CchMetric::settle(std::uint32_t arc, bool upward, std::vector<std::uint32_t>& raised) {
  // An eager metric's weights are exact: read where the searches read them, not the line beside.
  if (!options_.lazy_rises) return upward ? up_[arc] : down_[arc];
  const Way& me = way(arc, upward);
  const double w = me.weight;
  if (known_exact(arc, upward)) return w;
  // The weight's own witness first: settled, it is the cost of a real path, and where that equals
  // the weight (the common case) the lower bound is attained, so exact.
  const Witness own = me.via;
  const auto settled_sum = [&](Witness z) {
    // Both sides' lines asked for at once, so that their misses overlap: the first side's walk
    // may go deep before the second is read.
    __builtin_prefetch(&way(z.to_tail, !upward));
    __builtin_prefetch(&way(z.to_head, upward));
    // x→z→y upward, y→z→x downward, z below both (as unpack follows them).
    return upward ? add_cost(settle(z.to_tail, false, raised), settle(z.to_head, true, raised))
                  : add_cost(settle(z.to_head, false, raised), settle(z.to_tail, true, raised));
  };
  const double input = input_cost(arc, upward);
  Derived best{input, Witness{}};
  double own_s = kInfCost;
  if (!own.input()) {
    own_s = settled_sum(own);
    if (own_s < best.weight) best = Derived{own_s, own};
  }
  float& rival = lazy(arc, upward).rival;
  if (best.weight != w && best.weight > static_cast<double>(rival)) {
    // The witness rose above another way's bound. Every weight is at most its triangles' sums and
    // its input (a fall is carried up at once, a rise only raises them), so each triangle's sum
    // today is a lower bound of its real cost. The triangles are read once, those below the best
    // real path so far taken in order of their bounds, each settled one side at a time (a side
    // that lifts the sum to the best so far ends the triangle's turn, and its other side is left
    // as it is); once the next bound is no lower than the best settled sum, no triangle can beat
    // it. Settling raises weights only, so the bounds read stay bounds while the sides below them
    // are settled. What loses is the arc's new rival.
    double rest = own.input() ? kInfCost : best.via == own ? input : own_s;
    const std::size_t base = candidates_.size();
    for_each_lower_triangle(arc, upward, [&](double s, Witness z) {
      if (z == own) return;
      if (s < best.weight) {
        candidates_.push_back(Derived{s, z});
      } else {
        rest = std::min(rest, s);
      }
    });
    std::sort(candidates_.begin() + static_cast<std::ptrdiff_t>(base), candidates_.end(),
              [](const Derived& a, const Derived& b) { return a.weight < b.weight; });
    const std::size_t end = candidates_.size();
    for (std::size_t i = base; i < end; ++i) {
      const Derived c = candidates_[i];  // a copy: settling below pushes onto candidates_ too
      if (c.weight >= best.weight) {
        rest = std::min(rest, c.weight);  // the least of the bounds not looked at
        break;
      }
      // Its sides may have been raised since it was read, while settling others.
      const double bound = side_sum(c.via, upward);
      if (bound >= best.weight) {
        rest = std::min(rest, bound);
        continue;
      }
      // One side settled may already lift the sum to the best so far: the other side's weight
      // today is a lower bound of it, so the triangle loses without settling it.
      __builtin_prefetch(&way(upward ? c.via.to_head : c.via.to_tail, true));
      const double first = upward ? settle(c.via.to_tail, false, raised) : settle(c.via.to_head, false, raised);
      const double partial = add_cost(first, way(upward ? c.via.to_head : c.via.to_tail, true).weight);
      if (partial >= best.weight) {
        rest = std::min(rest, partial);
        continue;
      }
      const double s = add_cost(first, upward ? settle(c.via.to_head, true, raised) : settle(c.via.to_tail, true, raised));
      if (s < best.weight) {
        rest = std::min(rest, best.weight);
        best = Derived{s, c.via};
      } else {
        rest = std::min(rest, s);
      }
    }
    candidates_.resize(base);
    rival = std::numeric_limits<float>::infinity();
    lower_rival(arc, upward, rest);
  } else if (best.via != own) {
    // The input won over the witness's triangle, which is a rival from now on.
    lower_rival(arc, upward, own_s);
  }
  assert(best.weight >= w);
  // A tie through another witness moves no weight: nothing for the planner to repair. The witness
  // moves all the same, so that the weight is its witness's cost.
  if (best.weight != w) {
    raised.push_back(arc);
    set_weight(arc, upward, best.weight);
  }
  if (best.via != own) set_witness(arc, upward, best.via, best.via.input() ? kNoCchArc : topology_->tail(best.via.to_tail));
  lazy(arc, upward).exact = batch_;
  return best.weight;
}

}  // namespace corridor::planner
