// CenSurE keypoints (Agrawal, Konolige & Blas, ECCV 2008): bi-level centre-surround box filters
// evaluated in constant time per pixel on an integral image, extrema across position and scale,
// and a Harris-style test that drops responses lying along lines. Debian's OpenCV has no contrib
// StarDetector, so this is the project's own implementation of the DOB variant of the paper.
#pragma once

#include <opencv2/core.hpp>
#include <vector>

namespace corridor::localizer {

struct CenSurEOptions {
  int max_scale = 6;               // filter n: inner box (2n+1)², outer box (4n+1)², n = 1..max_scale
  float response_threshold = 6.0f;  // |mean inside − mean of the ring|, grey levels
  float line_threshold = 10.0f;    // ratio r of principal curvatures; trace²/det must stay below (r+1)²/r
};

// Keeps its work images between frames: at 640×480 and 30 fps, fresh allocations would cost
// more in page faults than the filtering itself.
class CenSurEDetector {
 public:
  explicit CenSurEDetector(const CenSurEOptions& options) : options_(options) {}
  // Keypoints with size = outer box side, response = |filter response|, octave = n.
  std::vector<cv::KeyPoint> detect(const cv::Mat& image8);

 private:
  CenSurEOptions options_;
  cv::Mat integral_;
  std::vector<cv::Mat> responses_;
  cv::Mat gx_, gy_, product_, ixx_, iyy_, ixy_;
};

inline std::vector<cv::KeyPoint> detect_censure(const cv::Mat& image8, const CenSurEOptions& options) {
  return CenSurEDetector(options).detect(image8);
}

// The bi-level filter response at one pixel and scale, from a CV_32S integral image (the reference
// the detector's row loops are tested against). Needs the outer box inside the image.
float censure_response(const cv::Mat& integral, int x, int y, int n);

}  // namespace corridor::localizer
