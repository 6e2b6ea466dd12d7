#include "maps/strongly_connected.hpp"

#include <algorithm>
#include <limits>

namespace corridor::maps {

Components strongly_connected_components(std::span<const std::uint32_t> first_out,
                                         std::span<const std::uint32_t> head) {
  constexpr std::uint32_t kUnvisited = std::numeric_limits<std::uint32_t>::max();
  const std::uint32_t n = static_cast<std::uint32_t>(first_out.size() - 1);
  Components out;
  out.component_of.assign(n, kUnvisited);
  std::vector<std::uint32_t> index(n, kUnvisited), low(n, 0), next_edge(n, 0);
  std::vector<std::uint8_t> on_stack(n, 0);
  std::vector<std::uint32_t> tarjan_stack, call_stack;
  std::vector<std::uint32_t> sizes;
  std::uint32_t counter = 0;

  // Recursion unrolled onto call_stack: country-sized graphs have chains far deeper than the C stack.
  for (std::uint32_t root = 0; root < n; ++root) {
    if (index[root] != kUnvisited) continue;
    call_stack.push_back(root);
    while (!call_stack.empty()) {
      const std::uint32_t u = call_stack.back();
      if (index[u] == kUnvisited) {
        index[u] = low[u] = counter++;
        next_edge[u] = first_out[u];
        tarjan_stack.push_back(u);
        on_stack[u] = 1;
      }
      bool descended = false;
      while (next_edge[u] < first_out[u + 1]) {
        const std::uint32_t v = head[next_edge[u]++];
        if (index[v] == kUnvisited) {
          call_stack.push_back(v);
          descended = true;
          break;
        }
        if (on_stack[v]) low[u] = std::min(low[u], index[v]);
      }
      if (descended) continue;
      call_stack.pop_back();
      if (!call_stack.empty()) low[call_stack.back()] = std::min(low[call_stack.back()], low[u]);
      if (low[u] == index[u]) {
        std::uint32_t size = 0;
        std::uint32_t w = 0;
        do {
          w = tarjan_stack.back();
          tarjan_stack.pop_back();
          on_stack[w] = 0;
          out.component_of[w] = out.count;
          ++size;
        } while (w != u);
        sizes.push_back(size);
        ++out.count;
      }
    }
  }
  if (!sizes.empty()) {
    out.largest = static_cast<std::uint32_t>(std::max_element(sizes.begin(), sizes.end()) - sizes.begin());
    out.largest_size = sizes[out.largest];
    for (std::uint32_t c = 0; c < sizes.size(); ++c) {
      if (c != out.largest) out.runner_up_size = std::max(out.runner_up_size, sizes[c]);
    }
  }
  return out;
}

}  // namespace corridor::maps
