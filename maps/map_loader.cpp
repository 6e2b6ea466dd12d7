#include "maps/map_loader.hpp"

#include "maps/intersection_geometry.hpp"
#include "maps/sumo_graph.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <cstdio>

#include "maps/errors.hpp"
#include "maps/graph_cache.hpp"

namespace corridor::maps {

std::filesystem::path cache_file_for(const std::filesystem::path& source, const std::filesystem::path& cache_dir) {
  std::error_code ec;
  const auto absolute = std::filesystem::weakly_canonical(source, ec);
  const std::string key = (ec ? source : absolute).string();
  std::uint64_t h = 14695981039346656037ULL;
  for (unsigned char ch : key) {
    h ^= ch;
    h *= 1099511628211ULL;
  }
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(h));
  std::string stem = source.filename().string();
  return cache_dir / (stem + "-" + hex + ".cgr");
}

bool is_sumo_net(const std::filesystem::path& file) {
  const std::string name = file.filename().string();
  return name.size() > 8 && name.ends_with(".net.xml");
}

SignalMap signal_plans_for(const std::filesystem::path& file, const RoadGraph& graph) {
  if (!is_sumo_net(file)) return signal_map_of(default_signal_plans(graph));
  const SumoNet net = read_sumo_net(file);
  const SumoGraph sumo = build_sumo_graph(net);
  if (sumo.graph.node_count() != graph.node_count() || sumo.graph.edge_count() != graph.edge_count()) {
    throw MapLoadError("'" + file.string() + "' changed since its graph was loaded");
  }
  return sumo_signal_map(sumo, net, sumo_signal_plans(net));
}

RoadGraph load_map(const std::filesystem::path& file, const MapLoadOptions& options, MapLoadInfo* info) {
  const auto start = std::chrono::steady_clock::now();
  MapLoadInfo local;
  auto finish = [&](RoadGraph graph) {
    local.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (info != nullptr) *info = local;
    return graph;
  };

  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec)) throw MapLoadError("map file not found: '" + file.string() + "'");
  if (is_sumo_net(file)) {
    // Fast to parse and never cached: the graph must match the net SUMO runs, edge for edge.
    return finish(build_sumo_graph(read_sumo_net(file)).graph);
  }
  if (looks_like_graph_cache(file)) {
    local.origin = MapLoadInfo::Origin::cache;
    local.cache_file = file;
    RoadGraph graph = read_graph_cache(file);
    // The side of the road was fixed when the cache was imported; a request for the other side
    // must not pass unnoticed with the first side's turn costs.
    if (options.import.left_hand_traffic && !graph.left_hand_traffic()) {
      throw MapLoadError("'" + file.string() +
                         "' is a graph cache imported for right-hand traffic; the side of the road is chosen on import "
                         "(corridor map import --left-hand-traffic), or pass the OSM file itself");
    }
    return finish(std::move(graph));
  }

  const CacheSource source = describe_source(file);
  std::filesystem::path cache;
  if (!options.cache_dir.empty()) {
    cache = cache_file_for(file, options.cache_dir);
    // The side of the road is part of the graph: one cache per side.
    if (options.import.left_hand_traffic) cache.replace_extension(".lht.cgr");
    if (std::filesystem::is_regular_file(cache, ec)) {
      try {
        CacheSource cached_source;
        RoadGraph graph = read_graph_cache(cache, &cached_source);
        if (cached_source == source) {
          local.origin = MapLoadInfo::Origin::cache;
          local.cache_file = cache;
          return finish(std::move(graph));
        }
        spdlog::info("event=cache_stale cache={} reason=source_changed", cache.string());
      } catch (const GraphCacheError& e) {
        spdlog::warn("event=cache_rejected cache={} reason=\"{}\"", cache.string(), e.what());
      }
    }
  }

  RoadGraph graph = import_osm(file, options.import, &local.import);
  if (!cache.empty()) {
    // A cache that cannot be written only costs time on the next start; the import itself succeeded.
    try {
      std::filesystem::create_directories(options.cache_dir, ec);
      write_graph_cache(cache, graph, source);
      local.cache_file = cache;
    } catch (const GraphCacheError& e) {
      spdlog::warn("event=cache_not_written reason=\"{}\"", e.what());
    }
  }
  return finish(std::move(graph));
}

}  // namespace corridor::maps
