#include "localizer/synth/stereo_renderer.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <random>

namespace corridor::localizer::synth {
namespace {

// Value noise that tiles: a random lattice with `cells` cells across, smoothly interpolated.
void add_periodic_noise(cv::Mat& img, int cells, double amplitude, std::mt19937_64& rng) {
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
  std::vector<float> lattice(static_cast<std::size_t>(cells * cells));
  for (float& v : lattice) v = unit(rng);
  const int n = img.rows;
  for (int y = 0; y < n; ++y) {
    const double fy = static_cast<double>(y) * cells / n;
    const int iy = static_cast<int>(fy);
    double ty = fy - iy;
    ty = ty * ty * (3 - 2 * ty);
    auto* row = img.ptr<float>(y);
    for (int x = 0; x < n; ++x) {
      const double fx = static_cast<double>(x) * cells / n;
      const int ix = static_cast<int>(fx);
      double tx = fx - ix;
      tx = tx * tx * (3 - 2 * tx);
      auto at = [&](int i, int j) { return lattice[static_cast<std::size_t>((j % cells) * cells + (i % cells))]; };
      const double top = at(ix, iy) + tx * (at(ix + 1, iy) - at(ix, iy));
      const double bottom = at(ix, iy + 1) + tx * (at(ix + 1, iy + 1) - at(ix, iy + 1));
      row[x] += static_cast<float>(amplitude * (top + ty * (bottom - top)));
    }
  }
}

cv::Mat noise_image(int size, double base, double contrast, std::mt19937_64& rng) {
  cv::Mat img(size, size, CV_32F, cv::Scalar(base));
  for (int cells = 4; cells <= size / 4; cells *= 2) {
    add_periodic_noise(img, cells, contrast * std::pow(16.0 / cells, 0.35), rng);
  }
  return img;
}

std::vector<cv::Mat> pyramid(cv::Mat base) {
  cv::max(base, 0.0, base);
  cv::min(base, 1.0, base);
  std::vector<cv::Mat> levels{base};
  while (levels.back().rows > 8) {
    cv::Mat next;
    cv::pyrDown(levels.back(), next);
    levels.push_back(next);
  }
  return levels;
}

// A façade 20.48 m square: plaster noise with a grid of windows (dark panes in light frames) and a
// ledge at every floor. The windows give the strong corners that real streets offer.
cv::Mat facade_image(int size, int windows_x, int floors, double albedo, std::mt19937_64& rng) {
  cv::Mat img = noise_image(size, albedo, 0.12, rng);
  const double cell_x = static_cast<double>(size) / windows_x;
  const double cell_y = static_cast<double>(size) / floors;
  std::uniform_real_distribution<double> jitter(-0.08, 0.08);
  for (int fy = 0; fy < floors; ++fy) {
    cv::rectangle(img, cv::Rect(0, static_cast<int>(fy * cell_y), size, static_cast<int>(cell_y * 0.06)),
                  cv::Scalar(albedo * 0.7), cv::FILLED);
    for (int wx = 0; wx < windows_x; ++wx) {
      const int x0 = static_cast<int>((wx + 0.28) * cell_x), y0 = static_cast<int>((fy + 0.25) * cell_y);
      const int w = static_cast<int>(cell_x * 0.44), h = static_cast<int>(cell_y * 0.5);
      cv::rectangle(img, cv::Rect(x0 - 6, y0 - 6, w + 12, h + 12), cv::Scalar(0.92), cv::FILLED);
      const double pane = 0.18 + jitter(rng) + 0.1 * (wx % 2);
      cv::rectangle(img, cv::Rect(x0, y0, w, h), cv::Scalar(pane), cv::FILLED);
      cv::line(img, {x0 + w / 2, y0}, {x0 + w / 2, y0 + h}, cv::Scalar(0.85), 4);
    }
  }
  return img;
}

// Everything about a wall hit that depends only on the column, so rows do not recompute it.
struct Hit {
  double depth;      // along the optical axis
  double u_m;        // texture coordinate along the wall
  double footprint;  // metres of wall per pixel, widened at grazing angles
  const Wall* wall;
};

}  // namespace

StereoRenderer::StereoRenderer(const RenderOptions& options, std::uint64_t texture_seed) : options_(options) {
  std::mt19937_64 rng(texture_seed);
  const int n = 1024;
  const int windows[4] = {4, 5, 3, 6};
  const int floors[4] = {6, 6, 7, 5};
  const double albedo[4] = {0.62, 0.48, 0.72, 0.55};
  for (int k = 0; k < 4; ++k) facades_.push_back({pyramid(facade_image(n, windows[k], floors[k], albedo[k], rng)), 0.02});
  facades_.push_back({pyramid(noise_image(n / 4, 0.45, 0.35, rng)), 0.01});  // clutter
  facades_.push_back({pyramid(noise_image(n / 4, 0.3, 0.4, rng)), 0.01});    // cars
  ground_ = {pyramid(noise_image(n, 0.38, 0.22, rng)), 0.01};
  overlay_ = {pyramid(noise_image(n / 2, 0.5, 0.5, rng)), 0.0731};
}

float StereoRenderer::sample(const Texture& t, double u_m, double v_m, double footprint_m) {
  const double lod = std::clamp(std::log2(std::max(footprint_m / t.texel_m, 1e-9)), 0.0,
                                static_cast<double>(t.levels.size() - 1));
  const int l0 = static_cast<int>(lod);
  const int l1 = std::min(l0 + 1, static_cast<int>(t.levels.size()) - 1);
  auto bilinear = [&](int level) {
    const cv::Mat& img = t.levels[static_cast<std::size_t>(level)];
    const int size = img.rows;
    const double texel = t.texel_m * (1 << level);
    const double x = u_m / texel - 0.5, y = v_m / texel - 0.5;
    const double fx = std::floor(x), fy = std::floor(y);
    const double ax = x - fx, ay = y - fy;
    auto wrap = [size](double i) {
      long k = static_cast<long>(i) % size;
      return static_cast<int>(k < 0 ? k + size : k);
    };
    const int x0 = wrap(fx), x1 = wrap(fx + 1), y0 = wrap(fy), y1 = wrap(fy + 1);
    const float* r0 = img.ptr<float>(y0);
    const float* r1 = img.ptr<float>(y1);
    return (1 - ay) * ((1 - ax) * r0[x0] + ax * r0[x1]) + ay * ((1 - ax) * r1[x0] + ax * r1[x1]);
  };
  const double a = bilinear(l0);
  if (l1 == l0) return static_cast<float>(a);
  return static_cast<float>(a + (lod - l0) * (bilinear(l1) - a));
}

cv::Mat StereoRenderer::render(const std::vector<Wall>& walls, const CameraPlacement& camera) const {
  const int ss = options_.supersample;
  const int w = options_.width * ss, h = options_.height * ss;
  const double f = options_.focal_px * ss;
  const double ccx = cx() * ss + (ss - 1) / 2.0, ccy = cy() * ss + (ss - 1) / 2.0;
  const double cam_h = options_.camera_height_m;
  const double far = options_.far_m;
  const double dx = std::cos(camera.heading_rad), dy = std::sin(camera.heading_rad);
  const double rx = dy, ry = -dx;  // the camera's right, in the map frame
  const maps::Point2 c = camera.position;

  // Only walls that can be within the far plane matter for this frame.
  std::vector<const Wall*> near;
  for (const Wall& wall : walls) {
    const double d = std::min(maps::distance_m(c, wall.a), maps::distance_m(c, wall.b));
    if (d < far + maps::distance_m(wall.a, wall.b)) near.push_back(&wall);
  }

  cv::Mat hi(h, w, CV_32F);
  cv::parallel_for_(cv::Range(0, w), [&](const cv::Range& columns) {
    std::vector<Hit> hits;
    for (int u = columns.start; u < columns.end; ++u) {
      const double a = (u - ccx) / f;
      const double ray_x = dx + a * rx, ray_y = dy + a * ry;  // per metre of depth
      const double ray_len = std::hypot(ray_x, ray_y);
      hits.clear();
      for (const Wall* wall : near) {
        // Solve c + t·ray = A + s·(B − A).
        const double ex = wall->b.x_m - wall->a.x_m, ey = wall->b.y_m - wall->a.y_m;
        const double denom = ray_x * ey - ray_y * ex;
        if (std::abs(denom) < 1e-12) continue;
        const double qx = wall->a.x_m - c.x_m, qy = wall->a.y_m - c.y_m;
        const double t = (qx * ey - qy * ex) / denom;
        const double s = (qx * ray_y - qy * ray_x) / denom;
        if (t > 0.05 && t < far && s >= 0 && s <= 1) {
          const double len = std::hypot(ex, ey);
          const double cos_inc = std::abs(ex * ray_y - ey * ray_x) / (len * ray_len);
          hits.push_back({t, wall->u_offset_m + s * len, t / f / std::sqrt(std::max(cos_inc, 0.15)), wall});
        }
      }
      std::sort(hits.begin(), hits.end(), [](const Hit& p, const Hit& q) { return p.depth < q.depth; });
      for (int v = 0; v < h; ++v) {
        const double k = (v - ccy) / f;  // height lost per metre of depth
        const double ground_t = k > 1e-9 ? cam_h / k : 1e18;
        float value = -1.0f;
        for (const Hit& hit : hits) {
          if (ground_t < hit.depth) break;
          const double z = cam_h - hit.depth * k;
          if (z < 0 || z > hit.wall->height_m) continue;
          const Wall& wall = *hit.wall;
          const Texture& tex = facades_[static_cast<std::size_t>(wall.texture)];
          const double detail = sample(tex, hit.u_m, z, hit.footprint);
          const double large = sample(overlay_, hit.u_m, z, std::max(hit.footprint, 0.3));
          value = static_cast<float>(255.0 * wall.shade * detail * (0.75 + 0.5 * large));
          break;
        }
        if (value < 0) {
          if (ground_t < far) {
            const double gx = c.x_m + ground_t * ray_x, gy = c.y_m + ground_t * ray_y;
            const double footprint = std::sqrt(ground_t * ground_t * ground_t / (cam_h * f * f));
            const double detail = sample(ground_, gx, gy, footprint);
            const double large = sample(overlay_, gx, gy, std::max(footprint, 0.3));
            value = static_cast<float>(255.0 * 0.85 * detail * (0.75 + 0.5 * large));
          } else {
            value = static_cast<float>(std::clamp(205.0 - 60.0 * k, 180.0, 245.0));  // sky
          }
        }
        hi.at<float>(v, u) = value;
      }
    }
  });
  if (ss == 1) return hi;
  cv::Mat out;
  cv::resize(hi, out, cv::Size(options_.width, options_.height), 0, 0, cv::INTER_AREA);
  return out;
}

}  // namespace corridor::localizer::synth
