#include "maps/osm_import.hpp"

#include <algorithm>
#include <limits>
#include <osmium/handler.hpp>
#include <osmium/handler/node_locations_for_ways.hpp>
#include <osmium/index/map/flex_mem.hpp>
#include <osmium/io/any_input.hpp>
#include <osmium/visitor.hpp>
#include <unordered_map>

#include "maps/errors.hpp"
#include "maps/osm_restrictions.hpp"
#include "maps/osm_tags.hpp"
#include "maps/progress.hpp"

namespace corridor::maps {
namespace {

constexpr double kKmhToMps = 1.0 / 3.6;

struct KeptWay {
  OsmWayId id;
  WayRules rules;
  std::uint32_t first_ref;  // refs/locations[first_ref .. first_ref + ref_count)
  std::uint32_t ref_count;
  std::uint32_t name;  // ids into RoadCollector::strings
  std::uint32_t ref;
};

std::string_view tag(const osmium::TagList& tags, const char* key) {
  const char* v = tags.get_value_by_key(key);
  return v == nullptr ? std::string_view{} : std::string_view{v};
}

// Streams ways (with node locations filled in by NodeLocationsForWays) and signal nodes.
class RoadCollector : public osmium::handler::Handler {
 public:
  void node(const osmium::Node& node) {
    const auto& t = node.tags();
    if (t.empty()) return;
    if (tag(t, "highway") == "traffic_signals") signals.push_back(node.id());
    NodeTags nt;
    nt.barrier = tag(t, "barrier");
    nt.bollard = tag(t, "bollard");
    nt.kerb = tag(t, "kerb");
    nt.maxheight = tag(t, "maxheight");
    nt.access = tag(t, "access");
    nt.vehicle = tag(t, "vehicle");
    nt.motor_vehicle = tag(t, "motor_vehicle");
    nt.motorcar = tag(t, "motorcar");
    nt.emergency = tag(t, "emergency");
    if (node_blocks_emergency(nt)) barriers.push_back(node.id());
    if (node_stops_vehicle(nt)) stops.push_back(node.id());
    // A height restrictor stops what is taller than its maxheight: a limit on the roads through it.
    if (nt.barrier == "height_restrictor" || !tag(t, "maxheight").empty()) {
      if (const auto h = parse_length_m(nt.maxheight)) height_limits.emplace_back(node.id(), *h);
    }
  }

  void way(const osmium::Way& way) {
    ++ways_read;
    const auto& t = way.tags();
    WayTags wt;
    wt.highway = tag(t, "highway");
    wt.route = tag(t, "route");
    if (wt.highway.empty() && wt.route.empty()) return;
    wt.duration = tag(t, "duration");
    wt.junction = tag(t, "junction");
    wt.oneway = tag(t, "oneway");
    wt.oneway_emergency = tag(t, "oneway:emergency");
    wt.maxspeed = tag(t, "maxspeed");
    wt.maxspeed_forward = tag(t, "maxspeed:forward");
    wt.maxspeed_backward = tag(t, "maxspeed:backward");
    wt.access = tag(t, "access");
    wt.vehicle = tag(t, "vehicle");
    wt.motor_vehicle = tag(t, "motor_vehicle");
    wt.motorcar = tag(t, "motorcar");
    wt.emergency = tag(t, "emergency");
    wt.area = tag(t, "area");
    wt.construction = tag(t, "construction");
    wt.oneway_motorcar = tag(t, "oneway:motorcar");
    wt.oneway_motor_vehicle = tag(t, "oneway:motor_vehicle");
    wt.oneway_vehicle = tag(t, "oneway:vehicle");
    wt.motorcar_forward = tag(t, "motorcar:forward");
    wt.motorcar_backward = tag(t, "motorcar:backward");
    wt.motor_vehicle_forward = tag(t, "motor_vehicle:forward");
    wt.motor_vehicle_backward = tag(t, "motor_vehicle:backward");
    wt.vehicle_forward = tag(t, "vehicle:forward");
    wt.vehicle_backward = tag(t, "vehicle:backward");
    wt.access_forward = tag(t, "access:forward");
    wt.access_backward = tag(t, "access:backward");
    wt.maxheight = tag(t, "maxheight");
    wt.maxwidth = tag(t, "maxwidth");
    wt.maxweight = tag(t, "maxweight");
    const auto rules = interpret_way(wt);
    if (!rules || way.nodes().size() < 2) return;
    ways.push_back({OsmWayId{way.id()}, *rules, static_cast<std::uint32_t>(refs.size()),
                    static_cast<std::uint32_t>(way.nodes().size()), strings.intern(tag(t, "name")),
                    strings.intern(tag(t, "ref"))});
    for (const auto& nr : way.nodes()) {
      refs.push_back(nr.ref());
      locations.push_back(nr.location());  // invalid when the extract cut the node off
    }
  }

  // Turn restrictions (maps/osm_restrictions.hpp).
  void relation(const osmium::Relation& rel) {
    if (!read_restriction(rel, restrictions)) ++restrictions_malformed;
  }

  std::size_t ways_read = 0;
  std::size_t restrictions_malformed = 0;
  std::vector<OsmRestriction> restrictions;
  std::vector<KeptWay> ways;
  std::vector<osmium::object_id_type> refs;
  std::vector<osmium::Location> locations;
  std::vector<osmium::object_id_type> signals;
  std::vector<osmium::object_id_type> barriers;  // nodes an emergency vehicle cannot pass
  std::vector<osmium::object_id_type> stops;     // barriers it passes but stops at (gates, toll booths)
  std::vector<std::pair<osmium::object_id_type, double>> height_limits;  // node, maxheight (m)
  StringInterner strings;
};

using LocationIndex = osmium::index::map::FlexMem<osmium::unsigned_object_id_type, osmium::Location>;

RoadCollector read_file(const std::filesystem::path& path, const OsmImportOptions& options) {
  RoadCollector collector;
  try {
    osmium::io::File file(path.string());
    osmium::io::Reader reader(file, osmium::osm_entity_bits::node | osmium::osm_entity_bits::way |
                                         osmium::osm_entity_bits::relation);
    LocationIndex index;
    osmium::handler::NodeLocationsForWays<LocationIndex> locations(index);
    locations.ignore_errors();  // ways crossing the extract's border reference absent nodes
    ProgressBar progress("importing " + path.filename().string(), reader.file_size());
    while (osmium::memory::Buffer buffer = reader.read()) {
      osmium::apply(buffer, locations, collector);
      if (options.show_progress) progress.update(reader.offset());
    }
    reader.close();
    progress.finish();
  } catch (const std::exception& e) {
    throw MapLoadError("cannot read OSM file '" + path.string() + "': " + e.what());
  }
  return collector;
}

}  // namespace

RoadGraph import_osm(const std::filesystem::path& path, const OsmImportOptions& options, OsmImportReport* report) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    throw MapLoadError("map file not found: '" + path.string() + "'");
  }
  RoadCollector c = read_file(path, options);
  std::sort(c.signals.begin(), c.signals.end());
  std::sort(c.barriers.begin(), c.barriers.end());
  std::sort(c.stops.begin(), c.stops.end());
  std::sort(c.height_limits.begin(), c.height_limits.end());
  auto node_height_limit = [&](osmium::object_id_type id) {
    const auto it = std::lower_bound(c.height_limits.begin(), c.height_limits.end(), std::make_pair(id, 0.0));
    return it != c.height_limits.end() && it->first == id ? it->second : 0.0;
  };
  // The tighter of two limits, where 0 means none.
  auto tighter = [](double a, double b) { return a <= 0 ? b : b <= 0 ? a : std::min(a, b); };

  // Junctions: nodes used more than once (by several ways or twice by one) and way ends. Barriers
  // are graph nodes too (a blocking one split into dead ends, one the vehicle stops at kept whole).
  // Every other node is inside a chain and only contributes geometry.
  std::vector<osmium::object_id_type> sorted_refs;
  sorted_refs.reserve(c.refs.size());
  for (std::size_t i = 0; i < c.refs.size(); ++i) {
    if (c.locations[i].valid()) sorted_refs.push_back(c.refs[i]);
  }
  std::sort(sorted_refs.begin(), sorted_refs.end());
  auto use_count = [&](osmium::object_id_type id) {
    auto [lo, hi] = std::equal_range(sorted_refs.begin(), sorted_refs.end(), id);
    return static_cast<std::size_t>(hi - lo);
  };
  auto is_signal = [&](osmium::object_id_type id) { return std::binary_search(c.signals.begin(), c.signals.end(), id); };
  auto is_barrier = [&](osmium::object_id_type id) {
    return std::binary_search(c.barriers.begin(), c.barriers.end(), id);
  };
  auto is_stop = [&](osmium::object_id_type id) { return std::binary_search(c.stops.begin(), c.stops.end(), id); };

  if (sorted_refs.empty()) throw MapLoadError("no drivable road in '" + path.string() + "'");

  // Projection centred on the bounding box of the road nodes.
  osmium::Box box;
  for (const auto& loc : c.locations) {
    if (loc.valid()) box.extend(loc);
  }
  GraphBuildInput in;
  in.strings = c.strings.take();
  in.origin = {(box.bottom_left().lat() + box.top_right().lat()) / 2.0,
               (box.bottom_left().lon() + box.top_right().lon()) / 2.0};
  const LocalProjection projection(in.origin);

  std::unordered_map<osmium::object_id_type, std::uint32_t> junction_index;
  junction_index.reserve(sorted_refs.size() / 4);
  auto add_node = [&](std::size_t ref_i) {
    const auto id = c.refs[ref_i];
    in.node_pos.push_back(projection.to_local({c.locations[ref_i].lat(), c.locations[ref_i].lon()}));
    in.node_osm.push_back(OsmNodeId{id});
    in.node_signalized.push_back(is_signal(id) ? 1 : 0);
    in.node_stop.push_back(is_stop(id) ? 1 : 0);
    return static_cast<std::uint32_t>(in.node_pos.size() - 1);
  };
  // A barrier the vehicle cannot pass becomes a separate dead end for every road that reaches it:
  // each side can be driven up to it (and a goal there reached), but no route passes through.
  auto junction = [&](std::size_t ref_i) {
    if (is_barrier(c.refs[ref_i])) return add_node(ref_i);
    auto [it, inserted] = junction_index.try_emplace(c.refs[ref_i], 0);
    if (inserted) it->second = add_node(ref_i);
    return it->second;
  };

  struct PendingSignal {
    std::uint32_t junction;
    double distance_m;
  };
  std::vector<PendingSignal> signal_marks;

  for (KeptWay& way : c.ways) {
    const std::uint32_t end = way.first_ref + way.ref_count;
    if (way.rules.duration_s > 0) {
      // A ferry's duration is for the whole crossing: its speed is the way's length over it, so
      // that each piece of the way takes its share (OSRM spreads it the same way).
      double length = 0.0;
      for (std::uint32_t k = way.first_ref + 1; k < end; ++k) {
        if (!c.locations[k - 1].valid() || !c.locations[k].valid()) continue;
        length += distance_m(projection.to_local({c.locations[k - 1].lat(), c.locations[k - 1].lon()}),
                             projection.to_local({c.locations[k].lat(), c.locations[k].lon()}));
      }
      // A duration that makes the crossing faster than any road, or that a float speed cannot hold,
      // is a tagging slip: the class's pace is kept.
      const double kmh = length / way.rules.duration_s / kKmhToMps;
      if (length > 0 && kmh >= 1e-4 && kmh <= 200.0) way.rules.forward_speed_kmh = way.rules.backward_speed_kmh = kmh;
    }
    std::uint32_t i = way.first_ref;
    while (i < end) {
      // A run of consecutive nodes with known locations; missing nodes split the way.
      while (i < end && !c.locations[i].valid()) ++i;
      std::uint32_t run_end = i;
      while (run_end < end && c.locations[run_end].valid()) ++run_end;
      if (run_end - i >= 2) {
        std::uint32_t from = junction(i);
        auto first_point = static_cast<std::uint32_t>(in.points.size());
        in.points.push_back(in.node_pos[from]);
        // A signal between two junctions marks the nearer one. A gate is a graph node but no
        // junction: the distances run from the last junction (`anchor`) across it.
        std::uint32_t anchor = from;
        double along = 0.0;
        double segment_height = tighter(way.rules.max_height_m, node_height_limit(c.refs[i]));
        std::vector<std::pair<std::uint32_t, double>> interior_signals;  // ref index, distance from anchor
        for (std::uint32_t k = i + 1; k < run_end; ++k) {
          const Point2 p = projection.to_local({c.locations[k].lat(), c.locations[k].lon()});
          along += distance_m(in.points.back(), p);
          segment_height = tighter(segment_height, node_height_limit(c.refs[k]));
          const bool real_junction = k + 1 == run_end || use_count(c.refs[k]) >= 2 || is_barrier(c.refs[k]);
          // A gate the vehicle stops at is a node of its own too, where its delay is charged.
          const bool is_junction = real_junction || is_stop(c.refs[k]);
          if (!is_junction) {
            in.points.push_back(p);
            if (is_signal(c.refs[k])) interior_signals.emplace_back(k, along);
            continue;
          }
          const std::uint32_t to = junction(k);
          in.points.push_back(in.node_pos[to]);
          RoadSegment seg;
          seg.from = from;
          seg.to = to;
          seg.first_point = first_point;
          seg.last_point = static_cast<std::uint32_t>(in.points.size() - 1);
          seg.forward = way.rules.forward;
          seg.backward = way.rules.backward;
          seg.forward_speed_mps = static_cast<float>(way.rules.forward_speed_kmh * kKmhToMps);
          seg.backward_speed_mps = static_cast<float>(way.rules.backward_speed_kmh * kKmhToMps);
          seg.way = way.id;
          seg.road_class = way.rules.road_class;
          seg.name = way.name;
          seg.ref = way.ref;
          seg.max_height_m = static_cast<float>(segment_height);
          seg.max_width_m = static_cast<float>(way.rules.max_width_m);
          seg.max_weight_t = static_cast<float>(way.rules.max_weight_t);
          seg.roundabout = way.rules.roundabout;
          in.segments.push_back(seg);
          // Past a barrier, the next segment starts from the barrier's other side.
          from = is_barrier(c.refs[k]) && k + 1 < run_end ? junction(k) : to;
          if (real_junction) {
            for (const auto& [ref_i, d] : interior_signals) {
              const double to_end = along - d;
              signal_marks.push_back(d <= to_end ? PendingSignal{anchor, d} : PendingSignal{to, to_end});
            }
            interior_signals.clear();
            anchor = from;
            along = 0.0;
          }
          segment_height = tighter(way.rules.max_height_m, node_height_limit(c.refs[k]));
          first_point = static_cast<std::uint32_t>(in.points.size());
          in.points.push_back(in.node_pos[from]);
        }
        in.points.pop_back();  // the run's last junction opened a segment that never came
      }
      i = run_end;
    }
  }
  for (const auto& mark : signal_marks) {
    if (mark.distance_m <= options.signal_to_junction_max_m) in.node_signalized[mark.junction] = 1;
  }

  OsmImportReport local;
  RoadGraph graph = build_road_graph(in, &local.graph);
  if (!c.restrictions.empty() || options.left_hand_traffic) {
    TurnRestrictions restrictions;
    const RestrictionResolver resolver(graph, c.restrictions);
    for (const auto& r : c.restrictions) {
      if (resolver.resolve(r, restrictions) > 0) {
        ++local.osm_restrictions_applied;
      } else {
        ++local.osm_restrictions_unresolved;
      }
    }
    RoadGraphData data = std::move(graph).take_data();
    data.restrictions = std::move(restrictions);
    if (options.left_hand_traffic) data.left_hand_traffic = {1};
    graph = RoadGraph(std::move(data));
  }
  local.osm_restrictions_unresolved += c.restrictions_malformed;
  local.osm_ways_read = c.ways_read;
  local.osm_ways_kept = c.ways.size();
  local.osm_signal_nodes = c.signals.size();
  local.osm_barrier_nodes = c.barriers.size();
  local.osm_stop_nodes = c.stops.size();
  if (report != nullptr) *report = local;
  return graph;
}

}  // namespace corridor::maps
