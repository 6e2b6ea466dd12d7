// Strong integer ids for graph nodes, edges and OSM objects, so that id spaces cannot be mixed.
#pragma once

#include <compare>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <type_traits>

namespace corridor {

template <class Tag, class Rep, Rep Invalid>
struct StrongId {
  using rep_type = Rep;
  static constexpr Rep kInvalidValue = Invalid;

  Rep v = Invalid;

  constexpr StrongId() = default;
  constexpr explicit StrongId(Rep value) : v(value) {}

  [[nodiscard]] constexpr bool valid() const { return v != Invalid; }
  [[nodiscard]] constexpr std::size_t index() const { return static_cast<std::size_t>(v); }
  friend constexpr auto operator<=>(StrongId, StrongId) = default;
};

// Graph indices are dense and 32-bit, as in RoutingKit; OSM ids are 64-bit and may be negative.
using NodeId = StrongId<struct NodeTag, std::uint32_t, std::numeric_limits<std::uint32_t>::max()>;
using EdgeId = StrongId<struct EdgeTag, std::uint32_t, std::numeric_limits<std::uint32_t>::max()>;
using OsmNodeId = StrongId<struct OsmNodeTag, std::int64_t, std::numeric_limits<std::int64_t>::min()>;
using OsmWayId = StrongId<struct OsmWayTag, std::int64_t, std::numeric_limits<std::int64_t>::min()>;

inline constexpr NodeId kInvalidNode{};
inline constexpr EdgeId kInvalidEdge{};

static_assert(std::is_trivially_copyable_v<NodeId> && sizeof(NodeId) == 4);
static_assert(std::is_trivially_copyable_v<EdgeId> && sizeof(EdgeId) == 4);
static_assert(std::is_trivially_copyable_v<OsmWayId> && sizeof(OsmWayId) == 8);

// A half-open range of consecutive ids, for `for (EdgeId e : graph.out_edges(u))`.
template <class Id>
class IdRange {
 public:
  class iterator {
   public:
    constexpr explicit iterator(typename Id::rep_type v) : v_(v) {}
    constexpr Id operator*() const { return Id{v_}; }
    constexpr iterator& operator++() {
      ++v_;
      return *this;
    }
    constexpr bool operator==(const iterator&) const = default;

   private:
    typename Id::rep_type v_;
  };
  constexpr IdRange(typename Id::rep_type begin, typename Id::rep_type end) : begin_(begin), end_(end) {}
  [[nodiscard]] constexpr iterator begin() const { return iterator{begin_}; }
  [[nodiscard]] constexpr iterator end() const { return iterator{end_}; }
  [[nodiscard]] constexpr std::size_t size() const { return end_ - begin_; }
  [[nodiscard]] constexpr bool empty() const { return begin_ == end_; }

 private:
  typename Id::rep_type begin_;
  typename Id::rep_type end_;
};

}  // namespace corridor

template <class Tag, class Rep, Rep Invalid>
struct std::hash<corridor::StrongId<Tag, Rep, Invalid>> {
  std::size_t operator()(corridor::StrongId<Tag, Rep, Invalid> id) const noexcept {
    return std::hash<Rep>{}(id.v);
  }
};
