// Dijkstra and A* from scratch on a SearchSpace: the baselines D* Lite is measured against, and its
// test oracles. The object keeps its arrays between queries, so a query costs what it visits.
#pragma once

#include <cstdint>
#include <vector>

#include "planner/route.hpp"
#include "planner/search_space.hpp"

namespace corridor::planner {

enum class Algorithm { dijkstra, astar, dstar_lite };
const char* to_string(Algorithm a);

struct SearchStats {
  std::uint64_t settled = 0;  // vertices taken off the queue for good
  std::uint64_t pushes = 0;
};

class OneToOneSearch {
 public:
  // Dijkstra when use_heuristic is false, A* with the landmark (ALT) heuristic otherwise.
  Route run(const SearchSpace& space, bool use_heuristic, SearchStats* stats = nullptr);

 private:
  void prepare(std::size_t vertex_count);

  std::vector<double> dist_;
  std::vector<std::uint32_t> parent_;   // previous vertex
  std::vector<EdgeId> parent_edge_;     // edge driven from the previous vertex
  std::vector<std::uint32_t> stamp_;    // dist_ is valid where stamp_ == round_
  std::vector<std::uint8_t> settled_;
  std::uint32_t round_ = 0;
};

}  // namespace corridor::planner
