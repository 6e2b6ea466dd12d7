// A top-down PNG of an estimated trajectory against ground truth (x right, z forward of the first
// camera, as KITTI plots them), with a scale bar.
#pragma once

#include <filesystem>
#include <vector>

#include "localizer/vo/kitti_format.hpp"

namespace corridor::localizer {

void write_trajectory_plot(const std::filesystem::path& png, const std::vector<Pose>& estimate,
                           const std::vector<Pose>* ground_truth);

}  // namespace corridor::localizer
