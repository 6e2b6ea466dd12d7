// `corridor preemption tables`: the seed paper's phase-decision tables, regenerated from the code.
#pragma once

#include <CLI/CLI.hpp>

namespace corridor::app {

void register_preemption_command(CLI::App& app);

}  // namespace corridor::app
