// Strongly connected components of a directed graph in CSR form (iterative Tarjan).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

namespace corridor::maps {

struct Components {
  std::vector<std::uint32_t> component_of;  // per node
  std::uint32_t count = 0;
  std::uint32_t largest = 0;  // id of the component with the most nodes (the first of equals)
  std::uint32_t largest_size = 0;  // its nodes
  std::uint32_t runner_up_size = 0;  // the nodes of the next largest (0 with a single component)
};

// head[first_out[u] .. first_out[u+1]) are the successors of u.
Components strongly_connected_components(std::span<const std::uint32_t> first_out,
                                         std::span<const std::uint32_t> head);

}  // namespace corridor::maps
