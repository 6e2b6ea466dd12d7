// Keypoints for the odometry: CenSurE by default, FAST or Harris (OpenCV core) as options, spread
// over the image by bucketing so that the motion is constrained by the whole field of view.
#pragma once

#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "localizer/vo/censure.hpp"

namespace corridor::localizer {

enum class DetectorKind { censure, fast, harris };

// Parses "censure", "fast" or "harris"; throws std::invalid_argument otherwise.
DetectorKind parse_detector_kind(const std::string& name);
std::string to_string(DetectorKind kind);

struct DetectorOptions {
  DetectorKind kind = DetectorKind::censure;
  int max_features = 900;
  int grid_cols = 10;
  int grid_rows = 6;
  int border_px = 12;  // keeps every patch used later inside the image
  CenSurEOptions censure;
  int fast_threshold = 15;
  double harris_quality = 0.0005;
};

// Holds the detector's work images from frame to frame.
class FeatureDetector {
 public:
  explicit FeatureDetector(const DetectorOptions& options) : options_(options), censure_(options.censure) {}
  std::vector<cv::KeyPoint> detect(const cv::Mat& image8);

 private:
  DetectorOptions options_;
  CenSurEDetector censure_;
};

inline std::vector<cv::KeyPoint> detect_features(const cv::Mat& image8, const DetectorOptions& options) {
  return FeatureDetector(options).detect(image8);
}

// Keeps the strongest keypoints of each grid cell, at most `max_total` overall.
std::vector<cv::KeyPoint> bucket_keypoints(std::vector<cv::KeyPoint> keypoints, cv::Size image, int cols, int rows,
                                           int max_total);

}  // namespace corridor::localizer
