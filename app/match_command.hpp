// `corridor match`: map-matches a GPX or CSV trace onto a map with the HMM matcher; `corridor bench
// match`: the matcher's throughput and accuracy on synthetic noisy drives of a map.
#pragma once

#include <CLI/CLI.hpp>

namespace corridor::app {

void register_match_command(CLI::App& app);
void register_match_bench(CLI::App& bench);

}  // namespace corridor::app
