// The metric half of a customizable contraction hierarchy: one weight per arc and direction of a
// CchTopology, derived from a TravelCost (one vehicle profile over the live cost overlay), so that
// every arc holds the cost of the cheapest path between its ends through lower ranks (with lazy
// rises, below: a lower bound of it). Built by a full customization; kept current by partial
// customization as congestion changes, which re-derives only the arcs an input change can reach
// (Dibbelt, Strasser & Wagner 2016, §5). The arcs whose weights moved are handed back, so the
// searches above can repair themselves.
//
// Most arc directions of a hierarchy over a turn graph can never be driven: a turn vertex reaches
// the next edge's vertex, rarely the way back, so on Porto 74 % of the arcs are open one way only
// and 17 % neither way. Which are open is fixed for a vehicle profile (restrictions, U-turns and
// the vehicle's size close inputs for good; congestion only raises costs, and a closure only adds
// an infinity on top), so the metric finds them once and customizes through the open ones alone
// (a "directed hierarchy").
#pragma once

#include <cassert>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "planner/cch_topology.hpp"
#include "planner/huge_page_allocator.hpp"
#include "planner/rising_id_queue.hpp"
#include "planner/travel_cost.hpp"

namespace corridor::planner {

struct CchMetricOptions {
  // false: every change is carried up at once and every weight is exact (the paper's partial
  // customization). true: rises wait until settle() finds them on a route; weights are lower
  // bounds. A lazy metric serves one planner: the arcs settle() raises are reported to that
  // planner alone, and another planner's values would stay on the old weights.
  bool lazy_rises = false;
};

// The lower triangle {z, x, y} (z below x below y) whose sum an arc {x, y}'s weight is: its sides
// {z, x} and {z, y}. Upward, x→z→y rides on {z, x} downward and {z, y} upward; downward, y→z→x the
// other way round. `to_tail` is kNoCchArc where the weight is the input turn's cost.
struct Witness {
  std::uint32_t to_tail = kNoCchArc;  // {z, x}
  std::uint32_t to_head = kNoCchArc;  // {z, y}
  [[nodiscard]] bool input() const { return to_tail == kNoCchArc; }
  friend bool operator==(const Witness&, const Witness&) = default;
};

struct CustomizationStats {
  std::uint64_t recomputed = 0;  // arc directions re-derived
  std::uint64_t changed = 0;     // of those, arcs whose weight moved
};

class CchMetric {
 public:
  // Full customization. `topology` and `cost` must outlive the metric; std::invalid_argument when
  // the topology was built over another graph than the cost's.
  CchMetric(const CchTopology& topology, const TravelCost& cost, CchMetricOptions options = {});

  // Weight of arc `arc` from its lower end to its higher end, and back; kInfCost for none. With
  // lazy rises, a lower bound until settle() makes it exact.
  [[nodiscard]] double up_s(std::uint32_t arc) const { return up_[arc]; }
  [[nodiscard]] double down_s(std::uint32_t arc) const { return down_[arc]; }
  [[nodiscard]] const CchTopology& topology() const { return *topology_; }
  // The higher neighbours z of rank r with r→z open (upper_out) or z→r open (upper_in), ascending,
  // each with the arc's id: the only arcs above r a path of this profile can ever take. In these
  // lists CchDownArc::tail holds the neighbour z, the higher end.
  [[nodiscard]] std::span<const CchDownArc> upper_out(std::uint32_t r) const { return upper_out_.of(r); }
  [[nodiscard]] std::span<const CchDownArc> upper_in(std::uint32_t r) const { return upper_in_.of(r); }
  // Whether arc `arc` is open from its lower end to its higher end (`upward`), or back.
  [[nodiscard]] bool open(std::uint32_t arc, bool upward) const { return (open_[arc] & (upward ? kUp : kDown)) != 0; }
  [[nodiscard]] const TravelCost& cost() const { return *cost_; }
  [[nodiscard]] bool lazy_rises() const { return options_.lazy_rises; }
  // Lazy rises: binds the metric to the one planner that settles it (planner/settled_replan.hpp).
  // False when another planner is bound already.
  bool bind_settler(const void* planner) {
    if (settler_ == nullptr) settler_ = planner;
    return settler_ == planner;
  }

  // The cost overlay behind `cost` changed these edges' conditions or these nodes' delays:
  // re-derive what they reach (lazy rises: only what got cheaper). Appends the ids of arcs whose
  // weights changed to `changed`.
  CustomizationStats edges_changed(std::span<const EdgeId> edges, std::vector<std::uint32_t>& changed);
  CustomizationStats nodes_changed(std::span<const NodeId> nodes, std::vector<std::uint32_t>& changed);

  // The cost of turn-graph arc `index` (an index into the turn graph's out-arcs): the turn plus
  // driving the edge it turns onto, exactly as SearchSpace charges it.
  [[nodiscard]] double input_s(std::uint32_t index) const;

  // The turn-graph vertices (not ranks) of the cheapest path that arc `arc` stands for, from
  // its lower end (`upward`) or its higher end, excluding the first vertex, appended to `out`.
  void unpack(std::uint32_t arc, bool upward, std::vector<std::uint32_t>& out) const;

  // Makes arc `arc`'s weight in one direction exact, and returns it: the witnesses it unpacks
  // through are settled first, bottom up, and a weight below the cost of its witness's path under
  // the inputs as last reported is re-derived from its triangles until the two agree. A lower
  // bound that agrees with the cost of a real path is the cheapest. Appends the arcs whose weight
  // it raised to `raised`. Does nothing on an eager metric, whose weights are always exact.
  double settle(std::uint32_t arc, bool upward, std::vector<std::uint32_t>& raised);

  // Checks every arc against its lower triangles and its input (lazy rises: that it lies at or
  // below them, that the kept input costs are today's, and that a weight settle() would return
  // without looking is the cost of the path it unpacks to); for tests. Empty when all hold.
  [[nodiscard]] std::string invariant_violation() const;

  [[nodiscard]] std::size_t memory_bytes() const;

 private:
  // Full customization; also closes `open` (kUp | kDown by arc, the open inputs on entry) under
  // the triangles, so that it ends holding every arc direction some path can drive.
  void customize_all(HugePageVector<std::uint8_t>& open);
  // Settles queued arcs in rank order of their lower end. An arc that changed offers its new
  // value through every triangle it is a lower side of: a cheaper path lowers the arc above at
  // once; a rise where the old value was the arc's minimum queues it to be re-derived.
  CustomizationStats propagate(std::vector<std::uint32_t>& changed);
  // Queues `arc` (saving its weights as they were before this round), to have the directions in
  // `derive` (kUp, kDown) re-derived from its input and triangles.
  static constexpr std::uint8_t kUp = 1, kDown = 2;
  void queue(std::uint32_t arc, std::uint8_t derive);
  // Triangle {x, y, z} offers `arc` (one of its upper sides) new_s in place of old_s, in one
  // direction; `middle` is its lowest vertex.
  void offer(std::uint32_t arc, bool upward, double old_s, double new_s, Witness via, std::uint32_t middle);
  void queue_turns_into(std::uint32_t turn_vertex);
  void queue_turns_out_of(std::uint32_t turn_vertex);
  // The weight a lower-triangle scan and the input give arc `arc` now in one direction, with its
  // witness.
  struct Derived {
    double weight;
    Witness via;
  };
  [[nodiscard]] Derived derive(std::uint32_t arc, bool upward) const;
  // f(sum, witness) for every lower triangle of arc `arc` open that way, its sum over today's
  // weights of its sides.
  template <class F>
  void for_each_lower_triangle(std::uint32_t arc, bool upward, F&& f) const;
  // settle()'s triangles still to look at, one run per call on the recursion's stack.
  std::vector<Derived> candidates_;
  // propagate()'s offers of one moved arc, gathered before they are made (prefetch_offer).
  struct Offer {
    std::uint32_t arc;
    bool upward;
    double side;  // the triangle's other side {x, z}
    Witness via;
  };
  std::vector<Offer> offers_;
  // Asks for the cache lines offer() reads of arc `arc` in that direction.
  void prefetch_offer(std::uint32_t arc, bool upward) const;
  // The sum over a triangle's sides today, the way asked: x→z→y upward, y→z→x downward.
  [[nodiscard]] double side_sum(Witness w, bool upward) const {
    return upward ? add_cost(way(w.to_tail, false).weight, way(w.to_head, true).weight)
                  : add_cost(way(w.to_head, false).weight, way(w.to_tail, true).weight);
  }
  // Whether `w` names two arcs {z, x} and {z, y} below arc {x, y}; for invariant_violation().
  [[nodiscard]] bool is_triangle(std::uint32_t arc, Witness w) const;
  // Which inputs the profile leaves open (kUp | kDown by arc), and the neighbour lists of the
  // open directions once customize_all has closed them under the triangles.
  [[nodiscard]] HugePageVector<std::uint8_t> open_inputs() const;
  void build_open_lists();

  const CchTopology* topology_;
  const TravelCost* cost_;
  CchMetricOptions options_;
  // The weights twice. In arrays of their own, for the searches, which read runs of an arc's
  // neighbours (ids ascend by lower end, so a vertex's arcs up are consecutive): eight to a cache
  // line.
  HugePageVector<double> up_;
  HugePageVector<double> down_;
  // And beside what customization and settle() read of one arc direction, in 16 bytes, with a lazy
  // metric's rest of it (below) in the next 16: a lazy metric's arc is one cache line, an eager
  // one's half of one. Customization offers to arcs scattered over a metric far larger than the
  // cache (over 100 MB on Porto), and settle() walks them; with a weight, its witness, its exact
  // batch and its rival each in an array of its own, an offer cost three misses, and an arc known
  // exact three (its batch, the climb's mark, then its weight), where it now costs two. An eager
  // metric has no lazy fields: 32 bytes an arc here, 48 with the dense weights (32 before); one
  // layout for both grew it by 60 MB on Porto, not 20, and slowed its searches by the larger
  // footprint. (A line per lazy arc where the array is 64-byte aligned, as huge-page arrays are;
  // a small map's array may straddle lines, which costs only speed.)
  struct Way {
    double weight;
    // The two lower sides of the triangle whose sum the weight is, or none where it is the input
    // turn's cost. Unpacking a route and settling follow them; kept as arc ids rather than the
    // triangle's middle, so that neither searches the middle's arc list for them.
    Witness via;
  };
  // Lazy rises: the batch the weight was last found exact in, the witness's middle z (or
  // kNoCchArc for the input; see batch_), and a lower bound of every other way to derive the
  // weight (the input where the witness is a triangle, and every open lower triangle but the
  // witness), rounded down to a float. Where the witness rose and its new sum is no dearer, the
  // witness holds, and settle() need not read the arc's triangles (on Porto's slowest replans,
  // about half the scans). Falls lower the rival as they are offered; rises only leave it lower
  // than it could be.
  struct LazyWay {
    std::uint32_t exact;
    std::uint32_t middle;
    float rival;
    std::uint32_t unused;
  };
  union alignas(16) Slot {
    Way way;
    LazyWay lazy;
    Slot() : way{} {}
  };
  static_assert(sizeof(Slot) == 16);
  // By arc, its up then its down direction: a Way each, followed by its LazyWay in a lazy metric
  // (one array of 16-byte slots, so that the two kinds differ only in the stride).
  HugePageVector<Slot> ways_;
  std::uint32_t lazy_shift_ = 0;  // 1 in a lazy metric: two slots a direction
  [[nodiscard]] std::size_t place_of(std::uint32_t arc, bool upward) const {
    return ((std::size_t{arc} << 1) | (upward ? 0U : 1U)) << lazy_shift_;
  }
  [[nodiscard]] Way& way(std::uint32_t arc, bool upward) { return ways_[place_of(arc, upward)].way; }
  [[nodiscard]] const Way& way(std::uint32_t arc, bool upward) const { return ways_[place_of(arc, upward)].way; }
  // Lazy metrics only: an eager one has no such slot, and the place would be the next Way.
  [[nodiscard]] LazyWay& lazy(std::uint32_t arc, bool upward) {
    assert(options_.lazy_rises);
    return ways_[place_of(arc, upward) + 1].lazy;
  }
  [[nodiscard]] const LazyWay& lazy(std::uint32_t arc, bool upward) const {
    assert(options_.lazy_rises);
    return ways_[place_of(arc, upward) + 1].lazy;
  }
  [[nodiscard]] const Witness& witness(std::uint32_t arc, bool upward) const { return way(arc, upward).via; }
  void set_weight(std::uint32_t arc, bool upward, double w) {
    way(arc, upward).weight = w;
    (upward ? up_ : down_)[arc] = w;
  }
  // Sets a witness; `middle` is its triangle's lowest vertex z (tail(w.to_tail)), or kNoCchArc.
  void set_witness(std::uint32_t arc, bool upward, Witness w, std::uint32_t middle) {
    way(arc, upward).via = w;
    if (options_.lazy_rises) lazy(arc, upward).middle = middle;
  }
  // A vertex's neighbours through open arc directions, each list ascending by neighbour: a CSR
  // per kind, indexed by rank. For a vertex v and a lower neighbour z: lower_out holds z where
  // v→z is open, lower_in where z→v is; upper_out and upper_in the same for higher neighbours.
  // CchDownArc::tail holds the neighbour, lower or higher.
  struct OpenLists {
    HugePageVector<std::uint32_t> first;
    HugePageVector<CchDownArc> entries;  // {neighbour, arc}
    [[nodiscard]] std::span<const CchDownArc> of(std::uint32_t r) const {
      return {entries.data() + first[r], first[r + 1] - first[r]};
    }
  };
  OpenLists lower_out_, lower_in_, upper_out_, upper_in_;
  HugePageVector<std::uint8_t> open_;  // by arc: kUp | kDown where open
  // One queued arc: its weights before this round, and which directions must be re-derived.
  struct Pending {
    double old_up;
    double old_down;
    std::uint8_t derive;
  };
  HugePageVector<std::uint32_t> slot_;     // by arc: 1 + its index in pending_, or 0 when not queued
  std::vector<Pending> pending_;
  // The queued arcs, taken in id order: ids follow the lower end's rank, and an arc only ever
  // queues arcs with higher lower ends.
  RisingIdQueue queue_;
  // Lazy rises: what settle() need not look at again. Each report of changes is a new batch. An
  // exact weight is the cost of the path its witness unpacks to, and that path runs through the
  // elimination subtree of the witness's middle z (its highest vertex below the arc's ends: every
  // lower neighbour is a descendant), so it can only have changed with a rise of an input whose
  // lower end lies in that subtree. A rise marks its lower end and the ancestors with the batch.
  // An arc found exact in a batch no earlier than the last rise below its witness's middle is
  // exact still, unless a fall has moved its weight since or its input rose while it was its
  // witness (both set its batch to 0), and settle() returns at once instead of walking what it
  // unpacks to. Marking falls by the weights they move, not by subtree, cut the Porto bench's
  // p50 and p99 by 5–10 %; reading the mark at the witness's middle rather than at the arc's
  // lower end (a subtree that holds the arc's every triangle) left 35 % fewer arcs to walk.
  std::uint32_t batch_ = 1;
  // By rank: the batch of the last input rise in its subtree, and the topology's parent(), side by
  // side: the climb reads both at each step, one cache miss instead of two.
  struct TreeMark {
    std::uint32_t changed_below;
    std::uint32_t parent;
  };
  HugePageVector<TreeMark> marks_;
  // Lazy rises: each input's cost as of the last change reported for it, both directions. A rise
  // is told from a fall by it, and settle() reads it instead of the graph and the overlay.
  struct Inputs {
    double up = kInfCost;
    double down = kInfCost;
  };
  HugePageVector<Inputs> inputs_;
  void lower_rival(std::uint32_t arc, bool upward, double s);
  [[nodiscard]] double input_cost(std::uint32_t arc, bool upward) const {
    if (options_.lazy_rises) return upward ? inputs_[arc].up : inputs_[arc].down;
    const std::uint32_t input = upward ? topology_->input(arc).up : topology_->input(arc).down;
    return input == kNoCchArc ? kInfCost : input_s(input);
  }
  void mark_changed(std::uint32_t arc);
  // Whether settle() may return arc `arc`'s weight in that direction without looking. An arc's
  // witness path runs through the subtree of its witness's middle z (the path's highest vertex
  // below the arc's ends; its sides' witnesses lie below z in turn), so only a rise below z can
  // have changed its cost. A weight that is its input's cost is reset (0) when that input rises.
  [[nodiscard]] bool known_exact(std::uint32_t arc, bool upward) const {
    const LazyWay& w = lazy(arc, upward);
    if (w.exact == 0) return false;
    return w.middle == kNoCchArc || w.exact >= marks_[w.middle].changed_below;
  }
  const void* settler_ = nullptr;
};

}  // namespace corridor::planner
