// `corridor sim` (one closed-loop SUMO run) and `corridor experiment sumo` (the experiment matrix).
#pragma once

#include <CLI/CLI.hpp>

namespace corridor::app {

void register_sim_command(CLI::App& app);
// Adds `sumo` under the `experiment` command.
void register_sumo_experiment(CLI::App& experiment);

}  // namespace corridor::app
