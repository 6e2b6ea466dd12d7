// `corridor experiment analytical`: the seed paper's analytical study (Figs. 5-9) on its hand-made
// graphs and on real maps, written as CSV tables, SVG plots and a Markdown summary.
#pragma once

#include <CLI/CLI.hpp>

namespace corridor::app {

void register_experiment_command(CLI::App& app);

}  // namespace corridor::app
