// Geographic coordinates at the system's edges and the local metric frame used everywhere inside.
#pragma once

#include <cmath>
#include <memory>

namespace GeographicLib {
class LocalCartesian;
}

namespace corridor::maps {

struct LatLon {
  double lat_deg = 0.0;
  double lon_deg = 0.0;
};

// Metric coordinates in the map's local east-north frame.
struct Point2 {
  double x_m = 0.0;
  double y_m = 0.0;
};

// sqrt of the sum rather than std::hypot: hypot's overflow care costs several times more, and local
// coordinates never come near overflow. This sits on every search's hot path.
inline double distance_m(Point2 a, Point2 b) {
  const double dx = a.x_m - b.x_m;
  const double dy = a.y_m - b.y_m;
  return std::sqrt(dx * dx + dy * dy);
}

// The nearest point to p on segment ab, as the fraction along it (0 at a, 1 at b).
inline double segment_fraction(Point2 p, Point2 a, Point2 b) {
  const double dx = b.x_m - a.x_m, dy = b.y_m - a.y_m;
  const double len2 = dx * dx + dy * dy;
  if (!(len2 > 0.0)) return 0.0;
  const double t = ((p.x_m - a.x_m) * dx + (p.y_m - a.y_m) * dy) / len2;
  return t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t);
}

// True when the coordinate is finite and inside WGS84 bounds.
bool is_valid_lat_lon(LatLon p);

// Projects WGS84 to a local tangent plane (GeographicLib::LocalCartesian) centred on the map, so that
// distances are metric and accurate over a city or a small country.
class LocalProjection {
 public:
  explicit LocalProjection(LatLon origin);
  ~LocalProjection();
  LocalProjection(const LocalProjection& other);
  LocalProjection& operator=(const LocalProjection& other);
  LocalProjection(LocalProjection&&) noexcept;
  LocalProjection& operator=(LocalProjection&&) noexcept;

  [[nodiscard]] Point2 to_local(LatLon p) const;
  [[nodiscard]] LatLon to_lat_lon(Point2 p) const;
  [[nodiscard]] LatLon origin() const { return origin_; }

 private:
  LatLon origin_;
  std::unique_ptr<GeographicLib::LocalCartesian> frame_;
};

}  // namespace corridor::maps
