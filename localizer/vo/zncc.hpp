// Zero-mean normalized cross-correlation of image patches, and the mutual ("marriage") assignment
// that accepts a match only when each feature is the other's best.
#pragma once

#include <opencv2/core.hpp>
#include <vector>

namespace corridor::localizer {

// A patch stored zero-mean with unit norm, so that ZNCC of two patches is their dot product.
class NormalizedPatch {
 public:
  // Returns an invalid patch when the window leaves the image or the patch is flat.
  static NormalizedPatch extract(const cv::Mat& image8, cv::Point2f centre, int radius);
  // Bilinear sampling at a sub-pixel centre.
  static NormalizedPatch extract_subpixel(const cv::Mat& image8, cv::Point2f centre, int radius);

  [[nodiscard]] bool valid() const { return !values_.empty(); }
  // In [-1, 1]; -1 when either patch is invalid or the sizes differ.
  [[nodiscard]] float zncc(const NormalizedPatch& other) const;

 private:
  static NormalizedPatch normalize(std::vector<float> values);
  std::vector<float> values_;
};

struct Candidate {
  int a = 0;  // index in the first set
  int b = 0;  // index in the second set
  float score = 0.0f;
};

// Keeps the candidates (a, b) where b is a's best-scoring partner and a is b's, above min_score.
std::vector<Candidate> mutual_best_matches(const std::vector<Candidate>& candidates, int count_a, int count_b,
                                           float min_score);

// Sub-pixel offset of a peak from three samples at -1, 0, +1 (parabola fit), clamped to ±0.5.
double parabola_peak_offset(double left, double centre, double right);

}  // namespace corridor::localizer
