// D* Lite's per-vertex state (g, rhs, place in the open list) in pages allocated on first write, so a
// mission whose search touches a small part of a metro graph holds only the pages it touched. One
// record per vertex keeps g, rhs and the heap position on one cache line, where three dense arrays
// cost three misses.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "planner/cost.hpp"
#include "planner/indexed_heap.hpp"

namespace corridor::planner {

struct VertexState {
  double g = kInfCost;
  double rhs = kInfCost;
  std::uint32_t heap_pos = kHeapAbsent;
};

class PagedVertexStates {
 public:
  // 256 vertices (6 KiB) per page: turn-graph vertex ids follow the Hilbert order of their nodes,
  // so a local search fills few pages, and a page is small next to a search's own working set. (On
  // a CCH, ids are ranks: the top separators share pages, the lower ancestors take about one page
  // per level.)
  static constexpr std::uint32_t kPageShift = 8;
  static constexpr std::uint32_t kPageSize = 1u << kPageShift;

  explicit PagedVertexStates(std::size_t vertex_count) : pages_((vertex_count + kPageSize - 1) >> kPageShift) {}

  // The state of v, or the initial one (g = rhs = ∞, not queued) if its page was never written.
  [[nodiscard]] const VertexState& get(std::uint32_t v) const {
    const auto& page = pages_[v >> kPageShift];
    return page ? page[v & (kPageSize - 1)] : kUntouched;
  }
  // Writable state of v, allocating its page on first use.
  VertexState& at(std::uint32_t v) {
    auto& page = pages_[v >> kPageShift];
    if (!page) {
      page = std::make_unique<VertexState[]>(kPageSize);
      ++allocated_;
    }
    return page[v & (kPageSize - 1)];
  }

  [[nodiscard]] std::size_t pages_allocated() const { return allocated_; }
  [[nodiscard]] std::size_t bytes() const {
    return allocated_ * kPageSize * sizeof(VertexState) + pages_.capacity() * sizeof(pages_[0]);
  }

  // The open list's positions live in the same records.
  class HeapPositions {
   public:
    explicit HeapPositions(PagedVertexStates* states) : states_(states) {}
    [[nodiscard]] std::uint32_t get(std::uint32_t v) const { return states_->get(v).heap_pos; }
    void set(std::uint32_t v, std::uint32_t i) { states_->at(v).heap_pos = i; }

   private:
    PagedVertexStates* states_;
  };

 private:
  static constexpr VertexState kUntouched{};
  std::vector<std::unique_ptr<VertexState[]>> pages_;
  std::size_t allocated_ = 0;
};

}  // namespace corridor::planner
