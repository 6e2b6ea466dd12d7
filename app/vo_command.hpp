// `corridor vo synth|run|compare`: synthetic stereo drives, the stereo odometry, and its evaluation.
#pragma once

#include <CLI/CLI.hpp>

namespace corridor::app {

void register_vo_command(CLI::App& app);

}  // namespace corridor::app
