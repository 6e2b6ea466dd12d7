// A 4-ary min-heap over vertex ids with decrease-, increase-key and removal, as D* Lite's open list
// needs. Keys are compared with operator<. Four children per node: a shallower heap, and the
// children of one node share a cache line or two. Where each id sits in the heap is kept by a
// Positions store: a dense array by default, or the caller's own (D* Lite keeps it in its paged
// per-vertex state).
#pragma once

#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

namespace corridor::planner {

inline constexpr std::uint32_t kHeapAbsent = std::numeric_limits<std::uint32_t>::max();

// One position per id in a dense array.
class DenseHeapPositions {
 public:
  explicit DenseHeapPositions(std::size_t id_count = 0) : pos_(id_count, kHeapAbsent) {}
  [[nodiscard]] std::uint32_t get(std::uint32_t id) const { return pos_[id]; }
  void set(std::uint32_t id, std::uint32_t i) { pos_[id] = i; }

 private:
  std::vector<std::uint32_t> pos_;
};

template <class Key, class Positions = DenseHeapPositions>
class IndexedHeap {
 public:
  static constexpr std::uint32_t kAbsent = kHeapAbsent;

  explicit IndexedHeap(std::size_t id_count = 0) : pos_(id_count) {}
  explicit IndexedHeap(Positions positions) : pos_(std::move(positions)) {}

  [[nodiscard]] bool empty() const { return heap_.empty(); }
  [[nodiscard]] std::size_t size() const { return heap_.size(); }
  [[nodiscard]] std::size_t capacity_bytes() const { return heap_.capacity() * sizeof(Entry); }
  [[nodiscard]] bool contains(std::uint32_t id) const { return pos_.get(id) != kAbsent; }
  [[nodiscard]] const Key& top_key() const { return heap_.front().key; }
  [[nodiscard]] std::uint32_t top() const { return heap_.front().id; }

  // Inserts, or changes the key of an id already present.
  void push_or_update(std::uint32_t id, const Key& key) {
    const std::uint32_t i = pos_.get(id);
    if (i == kAbsent) {
      heap_.push_back({key, id});
      sift_up(static_cast<std::uint32_t>(heap_.size() - 1));
      return;
    }
    const bool decreased = key < heap_[i].key;
    heap_[i].key = key;
    if (decreased) {
      sift_up(i);
    } else {
      sift_down(i);
    }
  }

  void remove(std::uint32_t id) {
    const std::uint32_t i = pos_.get(id);
    if (i == kAbsent) return;
    pos_.set(id, kAbsent);
    if (i + 1 == heap_.size()) {
      heap_.pop_back();
      return;
    }
    heap_[i] = heap_.back();
    heap_.pop_back();
    pos_.set(heap_[i].id, i);
    sift_down(i);
    sift_up(pos_.get(heap_[i].id) == i ? i : pos_.get(heap_[i].id));
  }

  void clear() {
    for (const auto& entry : heap_) pos_.set(entry.id, kAbsent);
    heap_.clear();
  }

  [[nodiscard]] Positions& positions() { return pos_; }
  [[nodiscard]] const Positions& positions() const { return pos_; }

 private:
  static constexpr std::uint32_t kArity = 4;

  struct Entry {
    Key key;
    std::uint32_t id;
  };

  void place(std::uint32_t i, Entry e) {
    pos_.set(e.id, i);
    heap_[i] = std::move(e);
  }
  void sift_up(std::uint32_t i) {
    Entry e = heap_[i];
    while (i > 0) {
      const std::uint32_t parent = (i - 1) / kArity;
      if (!(e.key < heap_[parent].key)) break;
      place(i, heap_[parent]);
      i = parent;
    }
    place(i, e);
  }
  void sift_down(std::uint32_t i) {
    Entry e = heap_[i];
    const auto n = static_cast<std::uint32_t>(heap_.size());
    while (true) {
      const std::uint32_t first = kArity * i + 1;
      if (first >= n) break;
      std::uint32_t child = first;
      const std::uint32_t end = first + kArity < n ? first + kArity : n;
      for (std::uint32_t c = first + 1; c < end; ++c) {
        if (heap_[c].key < heap_[child].key) child = c;
      }
      if (!(heap_[child].key < e.key)) break;
      place(i, heap_[child]);
      i = child;
    }
    place(i, e);
  }

  std::vector<Entry> heap_;
  Positions pos_;
};

}  // namespace corridor::planner
