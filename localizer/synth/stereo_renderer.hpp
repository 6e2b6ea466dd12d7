// Renders what a level pinhole camera sees of a StreetScene: textured façades, ground and sky.
// Walls are vertical and the camera does not roll or pitch, so each image column is one 2D ray
// cast through the wall segments (exact, not approximate), and each row then picks the surface
// hit at its height. Textures are procedural and mip-mapped, anchored to world coordinates, so a
// surface point looks the same from every frame; supersampling removes edge aliasing.
#pragma once

#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "localizer/synth/street_scene.hpp"

namespace corridor::localizer::synth {

struct RenderOptions {
  int width = 640;
  int height = 480;
  double focal_px = 700.0;
  double camera_height_m = 1.65;
  int supersample = 2;
  double far_m = 250.0;
};

struct CameraPlacement {
  maps::Point2 position;
  double heading_rad = 0.0;
};

class StereoRenderer {
 public:
  StereoRenderer(const RenderOptions& options, std::uint64_t texture_seed);

  // A CV_32F image with grey levels in [0, 255] (before noise and exposure).
  [[nodiscard]] cv::Mat render(const std::vector<Wall>& walls, const CameraPlacement& camera) const;

  [[nodiscard]] const RenderOptions& options() const { return options_; }
  [[nodiscard]] double cx() const { return (options_.width - 1) / 2.0; }
  [[nodiscard]] double cy() const { return (options_.height - 1) / 2.0; }

 private:
  struct Texture {
    std::vector<cv::Mat> levels;  // CV_32F in [0, 1], square, power-of-two sides; level 0 is finest
    double texel_m = 0.01;
  };
  [[nodiscard]] static float sample(const Texture& t, double u_m, double v_m, double footprint_m);

  RenderOptions options_;
  std::vector<Texture> facades_;  // 0-3 buildings, 4 kerb clutter, 5 cars
  Texture ground_;
  Texture overlay_;  // large-scale variation with another period, so textures never repeat exactly
};

}  // namespace corridor::localizer::synth
