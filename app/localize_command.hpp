// `corridor localize`: fuses GPS (with HDOP) and stereo odometry from a KITTI-layout sequence on a
// map, writes the matched positions, scores them against a truth drive, and can feed a live
// `corridor serve` with them at the sequence's pace.
#pragma once

#include <CLI/CLI.hpp>

namespace corridor::app {

void register_localize_command(CLI::App& app);

}  // namespace corridor::app
