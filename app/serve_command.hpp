// `corridor serve`: the dispatch server on a map, a database and an address.
#pragma once

#include <CLI/CLI.hpp>

namespace corridor::app {

void register_serve_command(CLI::App& app);

}  // namespace corridor::app
