// Backs the large arrays that searches read at random (a contraction hierarchy's metric and
// topology, over 100 MB on a metro map) with transparent huge pages, where the kernel grants them
// on request (`madvise`, Debian's default). With 4 KiB pages the TLB covers a few MB, so on such
// an array nearly every scattered read also walks the page table, which under a hypervisor's
// nested paging costs several more memory reads; 2 MiB pages make the walk rare. A hint only:
// where the kernel refuses, the memory is the same, in small pages. Arrays under 2 MiB gain
// nothing and come from the ordinary allocator.
#pragma once

#include <sys/mman.h>

#include <cstddef>
#include <cstdlib>
#include <limits>
#include <memory>
#include <new>
#include <vector>

namespace corridor::planner {

template <class T>
struct HugePageAllocator {
  using value_type = T;
  static constexpr std::size_t kHugePage = std::size_t{2} << 20;

  HugePageAllocator() = default;
  template <class U>
  explicit(false) HugePageAllocator(const HugePageAllocator<U>&) noexcept {}

  [[nodiscard]] T* allocate(std::size_t n) {
    if (n > std::numeric_limits<std::size_t>::max() / sizeof(T) - kHugePage) throw std::bad_array_new_length();
    const std::size_t bytes = n * sizeof(T);
    if (bytes < kHugePage) return std::allocator<T>{}.allocate(n);
    // Whole huge pages, aligned to one, so that every page of the array can be a huge one.
    const std::size_t rounded = (bytes + kHugePage - 1) / kHugePage * kHugePage;
    void* p = std::aligned_alloc(kHugePage, rounded);
    if (p == nullptr) throw std::bad_alloc();
    // Before the first write: the pages are granted when first touched. A refusal is no error.
    (void)::madvise(p, rounded, MADV_HUGEPAGE);
    return static_cast<T*>(p);
  }

  void deallocate(T* p, std::size_t n) noexcept {
    if (n * sizeof(T) < kHugePage) {
      std::allocator<T>{}.deallocate(p, n);
    } else {
      std::free(p);
    }
  }

  friend bool operator==(const HugePageAllocator&, const HugePageAllocator&) = default;
};

// A vector on huge pages once it holds 2 MiB or more.
template <class T>
using HugePageVector = std::vector<T, HugePageAllocator<T>>;

}  // namespace corridor::planner
