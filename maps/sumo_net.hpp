// Reads a SUMO .net.xml (edges, junctions with their right-of-way requests, connections and
// traffic-light programs) and turns each traffic light into a SignalPlan whose movements are SUMO's
// link indices, so that SUMO runs and the preemption engine share ids.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "maps/geo.hpp"
#include "maps/signal_plan.hpp"
#include "maps/sumo_vehicle_class.hpp"

namespace corridor::maps {

struct SumoLane {
  std::string id;
  double length_m = 0;
  double speed_mps = 0;
  std::vector<Point2> shape;  // SUMO's network coordinates
  SumoClasses allowed = kAllSumoClasses;  // its allow / disallow
};

struct SumoEdge {
  std::string id;
  std::string from;
  std::string to;
  std::string function;  // "internal" for junction-internal edges
  std::vector<SumoLane> lanes;

  [[nodiscard]] bool admits(SumoClasses cls) const {
    for (const SumoLane& l : lanes) {
      if ((l.allowed & cls) != 0) return true;
    }
    return false;
  }
};

struct SumoRequest {
  std::string foes;      // one char per junction link; the last char is link 0
  std::string response;  // same layout: links this one must yield to
};

struct SumoJunction {
  std::string id;
  std::string type;
  Point2 position;
  std::vector<SumoRequest> requests;  // by junction link index
};

struct SumoConnection {
  std::string from;
  std::string to;
  int from_lane = 0;
  int to_lane = 0;
  std::string via;  // first internal lane, ":<junction>_<link>_<lane>"
  std::string tl;
  int link_index = -1;
  char dir = 's';
  // A connection's own allow / disallow (a plain connection file's), which overrides its lanes'.
  std::optional<SumoClasses> allowed;
};

struct SumoTlPhase {
  double duration_s = 0;
  std::string state;
  double min_duration_s = 0;  // 0 when the program does not set minDur (static programs)
};

struct SumoTlLogic {
  std::string id;
  std::string program_id;
  std::string type;
  std::vector<SumoTlPhase> phases;
};

struct SumoNet {
  std::vector<SumoEdge> edges;
  std::vector<SumoJunction> junctions;
  std::vector<SumoConnection> connections;
  std::vector<SumoTlLogic> tl_logics;
  Point2 net_offset;
  std::string proj_parameter;
  std::string version;  // <net version="1.9">: the netconvert release that wrote the file

  // Lookups by id, from the index read_sumo_net builds (a linear scan before it is built).
  [[nodiscard]] const SumoEdge* edge(const std::string& id) const;
  [[nodiscard]] const SumoJunction* junction(const std::string& id) const;
  // Any lane, internal ones included, by its id; null when there is none.
  [[nodiscard]] const SumoLane* lane(const std::string& id) const;
  // Whether a vehicle of class `cls` may take the connection: its from and to lanes, and the
  // internal lane it crosses the junction on, admit the class (or the connection's own
  // permissions do, where it has them).
  [[nodiscard]] bool admits(const SumoConnection& c, SumoClasses cls) const;
  // (Re)builds the id index; call after changing edges or junctions.
  void build_index();

  std::unordered_map<std::string, std::size_t> edge_index;
  std::unordered_map<std::string, std::size_t> junction_index;
  std::unordered_map<std::string, std::pair<std::size_t, std::size_t>> lane_index;  // edge, lane
};

// Throws MapLoadError for a missing file or malformed XML, naming the file and line.
SumoNet read_sumo_net(const std::filesystem::path& file);

// The traffic-light programs (<tlLogic>) of an additional file, in file order. SUMO makes the last
// program loaded for a light its active one, so a scenario's additional programs replace the net's.
// Throws MapLoadError for a missing file or malformed XML.
std::vector<SumoTlLogic> read_sumo_tl_logics(const std::filesystem::path& file);

// The version attribute of a .net.xml's <net> element, read without parsing the rest; empty when
// the file has none. Throws MapLoadError for a missing file or XML that breaks before <net>.
std::string read_sumo_net_version(const std::filesystem::path& file);

// One traffic light's plan. plan.movements[i] is SUMO link i of the program (state[i]).
struct SumoSignalPlan {
  std::string tls_id;
  std::string program_id;
  SignalPlan plan;
  std::vector<const SumoConnection*> links;  // by link index; null where no connection names it
};

// Conflicts come from the junction requests (foes) of links at the same junction; links at
// different junctions of a joined traffic light never conflict. Phases are SUMO's phases with a
// green ('G' or 'g'); yellow_s is the longest yellow phase and all_red_s the longest all-red one,
// at least `min_all_red_s`. Throws MapLoadError when a program's states do not match its links.
std::vector<SumoSignalPlan> sumo_signal_plans(const SumoNet& net, double min_all_red_s = 1.0);

}  // namespace corridor::maps
