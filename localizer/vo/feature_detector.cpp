#include "localizer/vo/feature_detector.hpp"

#include <algorithm>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

namespace corridor::localizer {

DetectorKind parse_detector_kind(const std::string& name) {
  if (name == "censure") return DetectorKind::censure;
  if (name == "fast") return DetectorKind::fast;
  if (name == "harris") return DetectorKind::harris;
  throw std::invalid_argument("detector must be censure, fast or harris, got '" + name + "'");
}

std::string to_string(DetectorKind kind) {
  switch (kind) {
    case DetectorKind::censure: return "censure";
    case DetectorKind::fast: return "fast";
    case DetectorKind::harris: return "harris";
  }
  return "?";
}

std::vector<cv::KeyPoint> bucket_keypoints(std::vector<cv::KeyPoint> kps, cv::Size image, int cols, int rows,
                                           int max_total) {
  const int cells = cols * rows;
  const int per_cell = std::max(1, max_total / cells);
  std::sort(kps.begin(), kps.end(), [](const cv::KeyPoint& a, const cv::KeyPoint& b) { return a.response > b.response; });
  std::vector<int> count(static_cast<std::size_t>(cells), 0);
  std::vector<cv::KeyPoint> out;
  for (const auto& kp : kps) {
    const int cx = std::clamp(static_cast<int>(kp.pt.x * cols / image.width), 0, cols - 1);
    const int cy = std::clamp(static_cast<int>(kp.pt.y * rows / image.height), 0, rows - 1);
    int& c = count[static_cast<std::size_t>(cy * cols + cx)];
    if (c >= per_cell) continue;
    ++c;
    out.push_back(kp);
  }
  return out;
}

std::vector<cv::KeyPoint> FeatureDetector::detect(const cv::Mat& image8) {
  const DetectorOptions& o = options_;
  std::vector<cv::KeyPoint> kps;
  switch (o.kind) {
    case DetectorKind::censure:
      kps = censure_.detect(image8);
      break;
    case DetectorKind::fast:
      cv::FAST(image8, kps, o.fast_threshold, true);
      break;
    case DetectorKind::harris: {
      std::vector<cv::Point2f> corners;
      cv::goodFeaturesToTrack(image8, corners, 4 * o.max_features, o.harris_quality, 5.0, cv::noArray(), 3, true, 0.04);
      for (std::size_t i = 0; i < corners.size(); ++i) {
        // goodFeaturesToTrack returns corners strongest first; rank stands in for the response.
        kps.emplace_back(corners[i], 7.0f, -1.0f, static_cast<float>(corners.size() - i));
      }
      break;
    }
  }
  const float b = static_cast<float>(o.border_px);
  std::erase_if(kps, [&](const cv::KeyPoint& k) {
    return k.pt.x < b || k.pt.y < b || k.pt.x >= static_cast<float>(image8.cols) - b ||
           k.pt.y >= static_cast<float>(image8.rows) - b;
  });
  return bucket_keypoints(std::move(kps), image8.size(), o.grid_cols, o.grid_rows, o.max_features);
}

}  // namespace corridor::localizer
