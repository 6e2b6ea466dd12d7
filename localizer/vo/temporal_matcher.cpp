#include "localizer/vo/temporal_matcher.hpp"

#include <cmath>
#include <unordered_map>

namespace corridor::localizer {

FeatureSet describe_features(const cv::Mat& image8, const std::vector<cv::Point2f>& points, int radius) {
  FeatureSet set;
  set.points = points;
  set.patches.reserve(points.size());
  for (const auto& p : points) set.patches.push_back(NormalizedPatch::extract(image8, p, radius));
  return set;
}

std::vector<TemporalMatch> match_temporal(const FeatureSet& prev, const std::vector<cv::Point2f>& predicted,
                                          const FeatureSet& cur, const cv::Mat& cur_image,
                                          const TemporalMatchOptions& o) {
  // Grid of current features, cell = 16 px, for the window queries.
  constexpr int kCell = 16;
  std::unordered_map<long long, std::vector<int>> grid;
  auto key = [](int cx, int cy) { return (static_cast<long long>(cx) << 32) ^ static_cast<unsigned>(cy); };
  for (int j = 0; j < static_cast<int>(cur.points.size()); ++j) {
    if (!cur.patches[static_cast<std::size_t>(j)].valid()) continue;
    const auto& p = cur.points[static_cast<std::size_t>(j)];
    grid[key(static_cast<int>(p.x) / kCell, static_cast<int>(p.y) / kCell)].push_back(j);
  }
  std::vector<Candidate> candidates;
  for (int i = 0; i < static_cast<int>(prev.points.size()); ++i) {
    const auto& patch = prev.patches[static_cast<std::size_t>(i)];
    if (!patch.valid()) continue;
    const cv::Point2f c = predicted[static_cast<std::size_t>(i)];
    const int x0 = static_cast<int>(std::floor((c.x - o.search_half_width_px) / kCell));
    const int x1 = static_cast<int>(std::floor((c.x + o.search_half_width_px) / kCell));
    const int y0 = static_cast<int>(std::floor((c.y - o.search_half_height_px) / kCell));
    const int y1 = static_cast<int>(std::floor((c.y + o.search_half_height_px) / kCell));
    for (int gy = y0; gy <= y1; ++gy) {
      for (int gx = x0; gx <= x1; ++gx) {
        const auto it = grid.find(key(gx, gy));
        if (it == grid.end()) continue;
        for (const int j : it->second) {
          const auto& q = cur.points[static_cast<std::size_t>(j)];
          if (std::abs(q.x - c.x) > static_cast<float>(o.search_half_width_px) ||
              std::abs(q.y - c.y) > static_cast<float>(o.search_half_height_px)) {
            continue;
          }
          const float s = patch.zncc(cur.patches[static_cast<std::size_t>(j)]);
          if (s >= o.min_score) candidates.push_back({i, j, s});
        }
      }
    }
  }
  const auto mutual = mutual_best_matches(candidates, static_cast<int>(prev.points.size()),
                                          static_cast<int>(cur.points.size()), o.min_score);
  std::vector<TemporalMatch> out;
  out.reserve(mutual.size());
  for (const Candidate& m : mutual) {
    const auto& patch = prev.patches[static_cast<std::size_t>(m.a)];
    const cv::Point2f q = cur.points[static_cast<std::size_t>(m.b)];
    // Two parabola fits: on whole pixels, then on half pixels around the first estimate. One fit
    // alone pulls fractional shifts towards the nearest pixel by up to 0.2 px.
    auto score_at = [&](cv::Point2f c) {
      return static_cast<double>(patch.zncc(NormalizedPatch::extract_subpixel(cur_image, c, o.patch_radius)));
    };
    const double ox = parabola_peak_offset(score_at({q.x - 1, q.y}), m.score, score_at({q.x + 1, q.y}));
    const double oy = parabola_peak_offset(score_at({q.x, q.y - 1}), m.score, score_at({q.x, q.y + 1}));
    cv::Point2f c1{q.x + static_cast<float>(ox), q.y + static_cast<float>(oy)};
    const double centre = score_at(c1);
    const double ox2 = 0.5 * parabola_peak_offset(score_at({c1.x - 0.5f, c1.y}), centre, score_at({c1.x + 0.5f, c1.y}));
    const double oy2 = 0.5 * parabola_peak_offset(score_at({c1.x, c1.y - 0.5f}), centre, score_at({c1.x, c1.y + 0.5f}));
    const cv::Point2f refined{c1.x + static_cast<float>(ox2), c1.y + static_cast<float>(oy2)};
    out.push_back({m.a, m.b, refined, m.score});
  }
  return out;
}

}  // namespace corridor::localizer
