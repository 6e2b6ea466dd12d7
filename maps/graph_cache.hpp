// A versioned binary file holding a RoadGraph, so that a map is imported once and loaded in
// milliseconds afterwards. The header records the source file's size and mtime to detect staleness.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>

#include "maps/road_graph.hpp"

namespace corridor::maps {

// Bumped whenever the importer reads OSM differently, too: a cache stays valid only for the rules
// that built it.
inline constexpr std::uint32_t kGraphCacheVersion = 11;  // 2: names and refs; 3: ALT landmarks; 4: barriers, access; 5: turns;
                                                         // 6: every strongly connected component kept; 7: *_on_red not a ban;
                                                         // 8: landmarks on the main component only;
                                                         // 9: except as a vehicle class mask, ferries;
                                                         // 10: barriers the vehicle stops at;
                                                         // 11: open gates (access=yes) are no stop

struct CacheSource {
  std::uint64_t size_bytes = 0;
  std::int64_t mtime_ns = 0;
  friend bool operator==(const CacheSource&, const CacheSource&) = default;
};

// The size and modification time of a source file.
CacheSource describe_source(const std::filesystem::path& source);

// Writes atomically (temporary file, then rename). Throws GraphCacheError on I/O failure.
void write_graph_cache(const std::filesystem::path& file, const RoadGraph& graph, const CacheSource& source);

// Throws GraphCacheError for a missing, truncated, corrupt or other-version file.
RoadGraph read_graph_cache(const std::filesystem::path& file, CacheSource* source = nullptr);

// True when `file` starts with the cache magic, whatever its name.
bool looks_like_graph_cache(const std::filesystem::path& file);

}  // namespace corridor::maps
