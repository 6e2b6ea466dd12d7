#include "maps/geo.hpp"

#include <GeographicLib/LocalCartesian.hpp>

namespace corridor::maps {

bool is_valid_lat_lon(LatLon p) {
  return std::isfinite(p.lat_deg) && std::isfinite(p.lon_deg) && p.lat_deg >= -90.0 && p.lat_deg <= 90.0 &&
         p.lon_deg >= -180.0 && p.lon_deg <= 180.0;
}

LocalProjection::LocalProjection(LatLon origin)
    : origin_(origin), frame_(std::make_unique<GeographicLib::LocalCartesian>(origin.lat_deg, origin.lon_deg, 0.0)) {}

LocalProjection::~LocalProjection() = default;
LocalProjection::LocalProjection(const LocalProjection& other) : LocalProjection(other.origin_) {}
LocalProjection& LocalProjection::operator=(const LocalProjection& other) {
  if (this != &other) {
    origin_ = other.origin_;
    frame_ = std::make_unique<GeographicLib::LocalCartesian>(origin_.lat_deg, origin_.lon_deg, 0.0);
  }
  return *this;
}
LocalProjection::LocalProjection(LocalProjection&&) noexcept = default;
LocalProjection& LocalProjection::operator=(LocalProjection&&) noexcept = default;

Point2 LocalProjection::to_local(LatLon p) const {
  double x = 0, y = 0, z = 0;
  frame_->Forward(p.lat_deg, p.lon_deg, 0.0, x, y, z);
  return {x, y};
}

LatLon LocalProjection::to_lat_lon(Point2 p) const {
  double lat = 0, lon = 0, h = 0;
  frame_->Reverse(p.x_m, p.y_m, 0.0, lat, lon, h);
  return {lat, lon};
}

}  // namespace corridor::maps
