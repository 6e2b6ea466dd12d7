// `corridor bench replan`: the D* Lite vs A* / Dijkstra replanning benchmark, printed as JSON.
#pragma once

#include <CLI/CLI.hpp>

namespace corridor::app {

void register_bench_command(CLI::App& app);

}  // namespace corridor::app
