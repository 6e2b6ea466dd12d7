#include "planner/cch_metric.hpp"

#include <algorithm>
#include <functional>
#include <stdexcept>
#include <string>

namespace corridor::planner {

CchMetric::CchMetric(const CchTopology& topology, const TravelCost& cost)
    : topology_(&topology),
      cost_(&cost),
      up_(topology.arc_count(), kInfCost),
      down_(topology.arc_count(), kInfCost),
      via_up_(topology.arc_count(), kNoCchArc),
      via_down_(topology.arc_count(), kNoCchArc),
      slot_(topology.arc_count(), 0) {
  if (&topology.turns() != &cost.graph().turns()) {
    throw std::invalid_argument("the contraction hierarchy was built for another graph than the cost model's");
  }
  customize_all();
}

double CchMetric::input_s(std::uint32_t index) const {
  const maps::TurnGraph& turns = topology_->turns();
  const maps::TurnArc& a = topology_->turn_arc(index);
  const EdgeId in = turns.edge_of(topology_->turn_arc_source(index));
  const EdgeId onto = turns.edge_of(a.other);
  const double turn = cost_->turn_cost_s(in, a, onto);
  return turn >= kInfCost ? kInfCost : add_cost(turn, cost_->transit_s(onto));
}

void CchMetric::customize_all() {
  const CchTopology& t = *topology_;
  for (std::uint32_t arc = 0; arc < t.arc_count(); ++arc) {
    const CchTopology::Input& in = t.input(arc);
    up_[arc] = in.up == kNoCchArc ? kInfCost : input_s(in.up);
    down_[arc] = in.down == kNoCchArc ? kInfCost : input_s(in.down);
  }
  // Basic customization: every lower triangle {x, a, b} (x lowest) offers a→x→b and b→x→a. Going
  // up by x, an arc's weight is final before any arc above it reads it.
  for (std::uint32_t x = 0; x < t.vertex_count(); ++x) {
    const auto ups = t.up(x);
    const std::uint32_t base = t.first_up(x);
    for (std::size_t i = 0; i < ups.size(); ++i) {
      const std::uint32_t xa = base + static_cast<std::uint32_t>(i);
      const double a_to_x = down_[xa];
      const double x_to_a = up_[xa];
      if (a_to_x >= kInfCost && x_to_a >= kInfCost) continue;
      // The higher neighbours of x above a are higher neighbours of a too (chordality): walk both
      // ascending lists together to find the arcs {a, b}.
      const auto a_ups = t.up(ups[i]);
      std::size_t k = 0;
      for (std::size_t j = i + 1; j < ups.size(); ++j) {
        while (a_ups[k] < ups[j]) ++k;
        const std::uint32_t ab = t.first_up(ups[i]) + static_cast<std::uint32_t>(k);
        const std::uint32_t xb = base + static_cast<std::uint32_t>(j);
        const double up = add_cost(a_to_x, up_[xb]);
        const double down = add_cost(down_[xb], x_to_a);
        if (up < up_[ab]) {
          up_[ab] = up;
          via_up_[ab] = x;
        }
        if (down < down_[ab]) {
          down_[ab] = down;
          via_down_[ab] = x;
        }
      }
    }
  }
}

CchMetric::Derived CchMetric::derive(std::uint32_t arc) const {
  const CchTopology& t = *topology_;
  const CchTopology::Input& in = t.input(arc);
  Derived d{in.up == kNoCchArc ? kInfCost : input_s(in.up), in.down == kNoCchArc ? kInfCost : input_s(in.down),
            kNoCchArc, kNoCchArc};
  const std::uint32_t x = t.tail(arc), y = t.head(arc);
  // Lower triangles {z, x, y}: z below x joined to both. Both down lists are sorted by z.
  const auto dx = t.down(x);
  const auto dy = t.down(y);
  auto i = dx.begin();
  auto j = dy.begin();
  while (i != dx.end() && j != dy.end() && j->tail < x) {
    if (i->tail < j->tail) {
      ++i;
    } else if (j->tail < i->tail) {
      ++j;
    } else {
      const double up = add_cost(down_[i->arc], up_[j->arc]);
      const double down = add_cost(down_[j->arc], up_[i->arc]);
      if (up < d.up) {
        d.up = up;
        d.via_up = i->tail;
      }
      if (down < d.down) {
        d.down = down;
        d.via_down = i->tail;
      }
      ++i;
      ++j;
    }
  }
  return d;
}

void CchMetric::queue(std::uint32_t arc, bool derive) {
  if (arc == kNoCchArc) return;
  if (slot_[arc] != 0) {
    pending_[slot_[arc] - 1].derive |= derive;
    return;
  }
  pending_.push_back({up_[arc], down_[arc], derive});
  slot_[arc] = static_cast<std::uint32_t>(pending_.size());
  heap_.push_back(arc);
  std::push_heap(heap_.begin(), heap_.end(), std::greater<>());
}

void CchMetric::offer(std::uint32_t arc, bool upward, double old_s, double new_s, std::uint32_t via) {
  const double current = upward ? up_[arc] : down_[arc];
  if (new_s < current) {
    queue(arc, false);
    (upward ? up_[arc] : down_[arc]) = new_s;
    (upward ? via_up_[arc] : via_down_[arc]) = via;
  } else if (new_s > old_s && old_s == current) {
    // The path through this triangle was (one of) the arc's cheapest and got dearer: only a full
    // look at its triangles tells its new weight.
    queue(arc, true);
  }
}

void CchMetric::queue_turns_into(std::uint32_t v) {
  const CchTopology& t = *topology_;
  for (const maps::TurnArc& a : t.turns().arcs_in(v)) {
    if (a.other != v) queue(t.find_arc(t.rank(a.other), t.rank(v)));
  }
}

void CchMetric::queue_turns_out_of(std::uint32_t v) {
  const CchTopology& t = *topology_;
  for (const maps::TurnArc& a : t.turns().arcs_out(v)) {
    if (a.other != v) queue(t.find_arc(t.rank(v), t.rank(a.other)));
  }
}

CustomizationStats CchMetric::edges_changed(std::span<const EdgeId> edges, std::vector<std::uint32_t>& changed) {
  // An edge's conditions enter every turn onto it (the turn's input cost drives the edge), and the
  // turns onto its via-way copies.
  for (EdgeId e : edges) {
    queue_turns_into(e.v);
    for (std::uint32_t c : topology_->turns().copies_of(e)) queue_turns_into(c);
  }
  return propagate(changed);
}

CustomizationStats CchMetric::nodes_changed(std::span<const NodeId> nodes, std::vector<std::uint32_t>& changed) {
  // A node's delay enters every turn made at it: the turns out of the vertices standing there.
  const maps::RoadGraph& g = cost_->graph();
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
  // off the heap; the writes to it all come from arcs below it, which are settled before it too.
  while (!heap_.empty()) {
    std::pop_heap(heap_.begin(), heap_.end(), std::greater<>());
    const std::uint32_t arc = heap_.back();
    heap_.pop_back();
    const Pending p = pending_[slot_[arc] - 1];
    slot_[arc] = 0;
    if (p.derive) {
      ++stats.recomputed;
      const Derived d = derive(arc);
      up_[arc] = d.up;
      down_[arc] = d.down;
      via_up_[arc] = d.via_up;
      via_down_[arc] = d.via_down;
    }
    if (up_[arc] == p.old_up && down_[arc] == p.old_down) continue;
    ++stats.changed;
    changed.push_back(arc);
    // {x, y} is a lower side of every triangle {x, y, z} with z above x; the triangle's arc
    // between y and z is offered y→x→z and z→x→y.
    const std::uint32_t x = t.tail(arc), y = t.head(arc);
    // Only a direction that moved has anything to offer: y→x→z rides on y→x, z→x→y on x→y.
    const bool down_moved = down_[arc] != p.old_down;
    const bool up_moved = up_[arc] != p.old_up;
    const auto ups = t.up(x);
    const auto y_ups = t.up(y);
    std::size_t k = 0;
    for (std::size_t j = 0; j < ups.size(); ++j) {
      const std::uint32_t z = ups[j];
      if (z == y) continue;
      const std::uint32_t xz = t.first_up(x) + static_cast<std::uint32_t>(j);
      // A sibling still queued offers its weights as they were when it was queued: its own turn
      // will offer the step from there to its new weights, so each triangle's sum moves by one
      // chain of steps that starts at the sum the arc above was derived from.
      double x_to_z = up_[xz], z_to_x = down_[xz];
      if (slot_[xz] != 0) {
        x_to_z = pending_[slot_[xz] - 1].old_up;
        z_to_x = pending_[slot_[xz] - 1].old_down;
      }
      const bool offer_y_side = down_moved && x_to_z < kInfCost;  // y→x→z
      const bool offer_z_side = up_moved && z_to_x < kInfCost;    // z→x→y
      if (z > y) {
        while (y_ups[k] < z) ++k;  // z is a higher neighbour of y too (chordality)
      }
      if (!offer_y_side && !offer_z_side) continue;
      const bool y_lower = z > y;
      const std::uint32_t between = y_lower ? t.first_up(y) + static_cast<std::uint32_t>(k) : t.find_arc(z, y);
      if (offer_y_side) offer(between, y_lower, add_cost(p.old_down, x_to_z), add_cost(down_[arc], x_to_z), x);
      if (offer_z_side) offer(between, !y_lower, add_cost(z_to_x, p.old_up), add_cost(z_to_x, up_[arc]), x);
    }
  }
  pending_.clear();
  return stats;
}

void CchMetric::unpack(std::uint32_t arc, bool upward, std::vector<std::uint32_t>& out) const {
  const CchTopology& t = *topology_;
  const std::uint32_t x = t.tail(arc), y = t.head(arc);
  const std::uint32_t z = upward ? via_up_[arc] : via_down_[arc];
  if (z == kNoCchArc) {
    out.push_back(t.vertex_at(upward ? y : x));
    return;
  }
  // A shortcut: x→z→y upward, y→z→x downward, z below both.
  const std::uint32_t zx = t.find_arc(z, x), zy = t.find_arc(z, y);
  if (upward) {
    unpack(zx, false, out);
    unpack(zy, true, out);
  } else {
    unpack(zy, false, out);
    unpack(zx, true, out);
  }
}

std::string CchMetric::invariant_violation() const {
  const CchTopology& t = *topology_;
  for (std::uint32_t arc = 0; arc < t.arc_count(); ++arc) {
    const Derived d = derive(arc);
    if (d.up != up_[arc] || d.down != down_[arc]) {
      return "arc " + std::to_string(arc) + " holds " + std::to_string(up_[arc]) + "/" + std::to_string(down_[arc]) +
             " but its triangles give " + std::to_string(d.up) + "/" + std::to_string(d.down);
    }
    // Each finite weight's witness gives exactly it, so unpacking reproduces the weight.
    const CchTopology::Input& in = t.input(arc);
    for (const bool upward : {true, false}) {
      const double w = upward ? up_[arc] : down_[arc];
      if (w >= kInfCost) continue;
      const std::uint32_t z = upward ? via_up_[arc] : via_down_[arc];
      const std::uint32_t input = upward ? in.up : in.down;
      double witnessed = kInfCost;
      if (z == kNoCchArc) {
        if (input != kNoCchArc) witnessed = input_s(input);
      } else {
        const std::uint32_t zx = t.find_arc(z, t.tail(arc)), zy = t.find_arc(z, t.head(arc));
        if (zx != kNoCchArc && zy != kNoCchArc) {
          witnessed = upward ? add_cost(down_[zx], up_[zy]) : add_cost(down_[zy], up_[zx]);
        }
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
  return (up_.size() + down_.size()) * sizeof(double) +
         (via_up_.size() + via_down_.size() + slot_.size() + heap_.capacity()) * sizeof(std::uint32_t) +
         pending_.capacity() * sizeof(Pending);
}

}  // namespace corridor::planner
