// Frame-to-frame matching of left-image features: ZNCC of patches inside a search window around
// each feature's predicted position, mutual best matches only, then sub-pixel refinement.
#pragma once

#include <opencv2/core.hpp>
#include <vector>

#include "localizer/vo/zncc.hpp"

namespace corridor::localizer {

struct TemporalMatchOptions {
  int patch_radius = 5;
  int search_half_width_px = 60;
  int search_half_height_px = 30;
  float min_score = 0.8f;
};

struct FeatureSet {
  std::vector<cv::Point2f> points;
  std::vector<NormalizedPatch> patches;
};

FeatureSet describe_features(const cv::Mat& image8, const std::vector<cv::Point2f>& points, int patch_radius);

struct TemporalMatch {
  int previous = 0;
  int current = 0;
  cv::Point2f refined;  // sub-pixel position in the current image of the previous feature
  float score = 0.0f;
};

// `predicted[i]` is where previous feature i is expected in the current image.
std::vector<TemporalMatch> match_temporal(const FeatureSet& previous, const std::vector<cv::Point2f>& predicted,
                                          const FeatureSet& current, const cv::Mat& current_image8,
                                          const TemporalMatchOptions& options);

}  // namespace corridor::localizer
