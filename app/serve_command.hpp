// `corridor serve`: the dispatch server on a map, a database and an address.
#pragma once

#include <CLI/CLI.hpp>

#include "server/dispatch_service.hpp"

namespace corridor::app {

void register_serve_command(CLI::App& app);
// --planner-graph auto|turn-graph|hierarchy, for the server and its benchmark.
void add_planner_graph_option(CLI::App& cmd, server::PlannerGraph& out);

}  // namespace corridor::app
