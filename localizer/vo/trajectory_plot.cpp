#include "localizer/vo/trajectory_plot.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "localizer/vo/errors.hpp"

namespace corridor::localizer {

void write_trajectory_plot(const std::filesystem::path& png, const std::vector<Pose>& est,
                           const std::vector<Pose>* gt) {
  constexpr int kSize = 800, kMargin = 60;
  double min_x = 0, max_x = 0, min_z = 0, max_z = 0;
  auto extend = [&](const std::vector<Pose>& poses) {
    for (const auto& p : poses) {
      min_x = std::min(min_x, p.translation().x());
      max_x = std::max(max_x, p.translation().x());
      min_z = std::min(min_z, p.translation().z());
      max_z = std::max(max_z, p.translation().z());
    }
  };
  extend(est);
  if (gt) extend(*gt);
  const double span = std::max({max_x - min_x, max_z - min_z, 1.0});
  const double scale = (kSize - 2 * kMargin) / span;
  auto to_px = [&](const Pose& p) {
    return cv::Point(static_cast<int>(kMargin + (p.translation().x() - min_x) * scale),
                     static_cast<int>(kSize - kMargin - (p.translation().z() - min_z) * scale));
  };
  cv::Mat img(kSize, kSize, CV_8UC3, cv::Scalar(255, 255, 255));
  auto draw = [&](const std::vector<Pose>& poses, cv::Scalar colour) {
    for (std::size_t i = 1; i < poses.size(); ++i) cv::line(img, to_px(poses[i - 1]), to_px(poses[i]), colour, 2, cv::LINE_AA);
  };
  if (gt) draw(*gt, cv::Scalar(60, 160, 60));
  draw(est, cv::Scalar(40, 40, 220));
  cv::circle(img, to_px(est.front()), 6, cv::Scalar(0, 0, 0), 2, cv::LINE_AA);
  // Scale bar: a round number of metres near a fifth of the plot.
  const double raw = span / 5;
  const double bar = std::pow(10.0, std::floor(std::log10(raw))) * (raw / std::pow(10.0, std::floor(std::log10(raw))) >= 5 ? 5 : 1);
  const int bar_px = static_cast<int>(bar * scale);
  cv::line(img, {kMargin, kSize - 25}, {kMargin + bar_px, kSize - 25}, cv::Scalar(0, 0, 0), 2);
  cv::putText(img, std::to_string(static_cast<int>(bar)) + " m", {kMargin + bar_px + 8, kSize - 20},
              cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  cv::putText(img, "estimate", {kMargin, 30}, cv::FONT_HERSHEY_SIMPLEX, 0.6, cv::Scalar(40, 40, 220), 2, cv::LINE_AA);
  if (gt) cv::putText(img, "ground truth", {kMargin + 120, 30}, cv::FONT_HERSHEY_SIMPLEX, 0.6, cv::Scalar(60, 160, 60), 2, cv::LINE_AA);
  if (!cv::imwrite(png.string(), img)) throw SequenceError("cannot write plot " + png.string());
}

}  // namespace corridor::localizer
