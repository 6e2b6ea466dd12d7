// `corridor map import` and `corridor map info`: build a graph cache, and describe a loaded map.
#pragma once

#include <CLI/CLI.hpp>

namespace corridor::app {

void register_map_command(CLI::App& app);

}  // namespace corridor::app
