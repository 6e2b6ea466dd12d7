// The maps module's exception family: thrown at the boundary (files, user coordinates).
#pragma once

#include <stdexcept>
#include <string>

namespace corridor::maps {

class MapError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The map file is missing, unreadable, of an unknown format, or contains no drivable road.
class MapLoadError : public MapError {
 public:
  using MapError::MapError;
};

// A graph cache file is missing, truncated, of another version, or fails its checksum.
class GraphCacheError : public MapError {
 public:
  using MapError::MapError;
};

// A coordinate could not be placed on the road network.
class SnapError : public MapError {
 public:
  enum class Reason { invalid_coordinate, outside_map, too_far_from_road };
  SnapError(Reason reason, const std::string& message) : MapError(message), reason_(reason) {}
  [[nodiscard]] Reason reason() const { return reason_; }

 private:
  Reason reason_;
};

}  // namespace corridor::maps
