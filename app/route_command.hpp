// `corridor route`: one route between two coordinates, printed as a GeoJSON Feature.
#pragma once

#include <CLI/CLI.hpp>

namespace corridor::app {

void register_route_command(CLI::App& app);

}  // namespace corridor::app
