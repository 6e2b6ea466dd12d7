// `corridor vo synth|run|compare`: synthetic stereo drives, the stereo odometry, and its evaluation.
#pragma once

#include <CLI/CLI.hpp>
#include <filesystem>
#include <vector>

#include "localizer/vo/kitti_format.hpp"

namespace corridor::app {

void register_vo_command(CLI::App& app);

// The stereo odometry's poses for every frame of a KITTI-layout sequence, with default options,
// and the sequence's frame rate.
std::vector<localizer::Pose> vo_poses(const std::filesystem::path& sequence, double* frame_rate_hz = nullptr);

}  // namespace corridor::app
