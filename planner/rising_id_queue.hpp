// A set of integer ids in [0, n), taken out smallest first, built for sweeps that only ever add
// ids above the one last taken out: the partial customization of a contraction hierarchy, whose
// writes go from an arc to arcs with higher lower ends (planner/cch_metric.hpp). Two levels of
// bits: adding is O(1), and such a sweep scans each summary word at most once, where a binary
// heap pays a logarithm with scattered reads on every add and every take. Ids may be added in any
// order before the first take of a sweep; after it, an id below the last one taken would still
// come out in order but cost a rescan, so debug builds refuse it.
#pragma once

#include <bit>
#include <cassert>
#include <cstdint>
#include <vector>

namespace corridor::planner {

class RisingIdQueue {
 public:
  explicit RisingIdQueue(std::size_t n) : bits_((n + 63) / 64, 0), summary_((bits_.size() + 63) / 64, 0) {}

  [[nodiscard]] bool empty() const { return size_ == 0; }

  // Adds `id`; a no-op when it is queued. Once this sweep has taken an id out, `id` must be above
  // it (the sweep ends when the queue runs empty).
  void push(std::uint32_t id) {
    assert(!taking_ || id > last_taken_);
    std::uint64_t& word = bits_[id / 64];
    const std::uint64_t bit = std::uint64_t{1} << (id % 64);
    if ((word & bit) != 0) return;
    word |= bit;
    summary_[id / 4096] |= std::uint64_t{1} << ((id / 64) % 64);
    if (size_ == 0 || id / 64 < cursor_) cursor_ = id / 64;
    ++size_;
  }

  // Takes out the smallest queued id. The queue must not be empty.
  std::uint32_t pop() {
    assert(size_ > 0);
    // The smallest non-empty word at or after the cursor: the cursor's summary word masked below
    // it, then the summary words after it.
    std::size_t s = cursor_ / 64;
    std::uint64_t pending = summary_[s] & (~std::uint64_t{0} << (cursor_ % 64));
    while (pending == 0) pending = summary_[++s];
    cursor_ = s * 64 + static_cast<std::size_t>(std::countr_zero(pending));
    std::uint64_t& word = bits_[cursor_];
    const unsigned bit = static_cast<unsigned>(std::countr_zero(word));
    word &= word - 1;
    if (word == 0) summary_[s] &= ~(std::uint64_t{1} << (cursor_ % 64));
    --size_;
    const auto id = static_cast<std::uint32_t>(cursor_ * 64 + bit);
#ifndef NDEBUG
    taking_ = size_ > 0;
    last_taken_ = id;
#endif
    return id;
  }

  [[nodiscard]] std::size_t memory_bytes() const { return (bits_.capacity() + summary_.capacity()) * sizeof(std::uint64_t); }

 private:
  std::vector<std::uint64_t> bits_;     // one bit per id
  std::vector<std::uint64_t> summary_;  // one bit per word of bits_: it has a bit set
  std::size_t cursor_ = 0;              // no queued id lies in a word before this one
  std::size_t size_ = 0;
#ifndef NDEBUG
  bool taking_ = false;  // a sweep has taken an id out and the queue is not yet empty
  std::uint32_t last_taken_ = 0;
#endif
};

}  // namespace corridor::planner
