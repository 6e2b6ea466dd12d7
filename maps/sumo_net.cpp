#include "maps/sumo_net.hpp"

#include <expat.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>

#include "maps/errors.hpp"

namespace corridor::maps {
namespace {

struct Attributes {
  const char** list;
  [[nodiscard]] const char* get(const char* key) const {
    for (const char** a = list; *a != nullptr; a += 2) {
      if (std::strcmp(a[0], key) == 0) return a[1];
    }
    return nullptr;
  }
  [[nodiscard]] std::string str(const char* key) const {
    const char* v = get(key);
    return v == nullptr ? std::string{} : std::string{v};
  }
  [[nodiscard]] double number(const char* key, double fallback = 0.0) const {
    const char* v = get(key);
    if (v == nullptr) return fallback;
    char* end = nullptr;
    const double d = std::strtod(v, &end);
    return end == v ? fallback : d;
  }
};

std::vector<Point2> parse_shape(const std::string& text) {
  std::vector<Point2> out;
  std::istringstream in(text);
  std::string pair;
  while (in >> pair) {
    const auto comma = pair.find(',');
    if (comma == std::string::npos) continue;
    out.push_back({std::strtod(pair.c_str(), nullptr), std::strtod(pair.c_str() + comma + 1, nullptr)});
  }
  return out;
}

struct ParseState {
  SumoNet net;
  std::string error;
  XML_Parser parser = nullptr;
  bool stop_at_net = false;  // read_sumo_net_version: stop at the <net> element
};

void on_start(void* user, const char* name, const char** attrs) {
  auto& st = *static_cast<ParseState*>(user);
  const Attributes a{attrs};
  SumoNet& net = st.net;
  if (std::strcmp(name, "edge") == 0) {
    net.edges.push_back({a.str("id"), a.str("from"), a.str("to"), a.str("function"), {}});
  } else if (std::strcmp(name, "lane") == 0 && !net.edges.empty()) {
    net.edges.back().lanes.push_back({a.str("id"), a.number("length"), a.number("speed"), parse_shape(a.str("shape")),
                                      parse_sumo_permissions(a.str("allow"), a.str("disallow"))});
  } else if (std::strcmp(name, "junction") == 0) {
    net.junctions.push_back({a.str("id"), a.str("type"), {a.number("x"), a.number("y")}, {}});
  } else if (std::strcmp(name, "request") == 0 && !net.junctions.empty()) {
    const auto index = static_cast<std::size_t>(a.number("index", -1));
    auto& requests = net.junctions.back().requests;
    if (index >= 100000) {
      st.error = "request without a valid index";
      return;
    }
    if (requests.size() <= index) requests.resize(index + 1);
    requests[index] = {a.str("foes"), a.str("response")};
  } else if (std::strcmp(name, "connection") == 0) {
    SumoConnection c;
    c.from = a.str("from");
    c.to = a.str("to");
    c.from_lane = static_cast<int>(a.number("fromLane"));
    c.to_lane = static_cast<int>(a.number("toLane"));
    c.via = a.str("via");
    c.tl = a.str("tl");
    c.link_index = static_cast<int>(a.number("linkIndex", -1));
    const std::string dir = a.str("dir");
    c.dir = dir.empty() ? 's' : dir[0];
    if (a.get("allow") != nullptr || a.get("disallow") != nullptr) c.allowed = parse_sumo_permissions(a.str("allow"), a.str("disallow"));
    net.connections.push_back(std::move(c));
  } else if (std::strcmp(name, "tlLogic") == 0) {
    net.tl_logics.push_back({a.str("id"), a.str("programID"), a.str("type"), {}});
  } else if (std::strcmp(name, "phase") == 0 && !net.tl_logics.empty()) {
    net.tl_logics.back().phases.push_back({a.number("duration"), a.str("state"), a.number("minDur", 0.0)});
  } else if (std::strcmp(name, "net") == 0) {
    net.version = a.str("version");
    if (st.stop_at_net) XML_StopParser(st.parser, XML_FALSE);
  } else if (std::strcmp(name, "location") == 0) {
    const auto offset = parse_shape(a.str("netOffset"));
    if (!offset.empty()) net.net_offset = offset.front();
    net.proj_parameter = a.str("projParameter");
  }
}

// The junction-internal link index from a via lane ":<junction>_<link>_<lane>".
std::optional<std::size_t> junction_link_index(const std::string& via, const std::string& junction) {
  const std::string prefix = ":" + junction + "_";
  if (via.rfind(prefix, 0) != 0) return std::nullopt;
  const std::string rest = via.substr(prefix.size());
  const auto underscore = rest.find('_');
  if (underscore == std::string::npos || underscore == 0) return std::nullopt;
  for (std::size_t i = 0; i < underscore; ++i) {
    if (!std::isdigit(static_cast<unsigned char>(rest[i]))) return std::nullopt;
  }
  return static_cast<std::size_t>(std::stoul(rest.substr(0, underscore)));
}

// foes and response strings hold link 0 in their last character.
bool bit(const std::string& bits, std::size_t link) {
  return link < bits.size() && bits[bits.size() - 1 - link] == '1';
}


Turn turn_of(char dir) {
  switch (dir) {
    case 'r':
    case 'R': return Turn::right;
    case 'l':
    case 'L':
    case 't': return Turn::left;
    default: return Turn::through;
  }
}

}  // namespace

const SumoEdge* SumoNet::edge(const std::string& id) const {
  if (!edge_index.empty()) {
    const auto it = edge_index.find(id);
    return it == edge_index.end() ? nullptr : &edges[it->second];
  }
  for (const auto& e : edges) {
    if (e.id == id) return &e;
  }
  return nullptr;
}

const SumoJunction* SumoNet::junction(const std::string& id) const {
  if (!junction_index.empty()) {
    const auto it = junction_index.find(id);
    return it == junction_index.end() ? nullptr : &junctions[it->second];
  }
  for (const auto& j : junctions) {
    if (j.id == id) return &j;
  }
  return nullptr;
}

const SumoLane* SumoNet::lane(const std::string& id) const {
  if (!lane_index.empty()) {
    const auto it = lane_index.find(id);
    return it == lane_index.end() ? nullptr : &edges[it->second.first].lanes[it->second.second];
  }
  for (const auto& e : edges) {
    for (const auto& l : e.lanes) {
      if (l.id == id) return &l;
    }
  }
  return nullptr;
}

bool SumoNet::admits(const SumoConnection& c, SumoClasses cls) const {
  if (c.allowed) return (*c.allowed & cls) != 0;
  const auto lane_admits = [&](const std::string& edge_id, int index) {
    const SumoEdge* e = edge(edge_id);
    if (e == nullptr || index < 0 || static_cast<std::size_t>(index) >= e->lanes.size()) return false;
    return (e->lanes[static_cast<std::size_t>(index)].allowed & cls) != 0;
  };
  if (!lane_admits(c.from, c.from_lane) || !lane_admits(c.to, c.to_lane)) return false;
  // The internal lane carries the connection's own permissions where netconvert set them.
  if (const SumoLane* via = c.via.empty() ? nullptr : lane(c.via)) return (via->allowed & cls) != 0;
  return true;
}

void SumoNet::build_index() {
  edge_index.clear();
  junction_index.clear();
  lane_index.clear();
  for (std::size_t i = 0; i < edges.size(); ++i) {
    edge_index.emplace(edges[i].id, i);
    for (std::size_t k = 0; k < edges[i].lanes.size(); ++k) lane_index.emplace(edges[i].lanes[k].id, std::pair(i, k));
  }
  for (std::size_t i = 0; i < junctions.size(); ++i) junction_index.emplace(junctions[i].id, i);
}

namespace {

// Parses a SUMO XML file (net or additional) into st.net. Returns false when the parse stopped
// early on request (stop_at_net).
bool parse_sumo_xml(const std::filesystem::path& file, const char* what, ParseState& st) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw MapLoadError(std::string(what) + " not found: '" + file.string() + "'");
  std::unique_ptr<XML_ParserStruct, decltype(&XML_ParserFree)> parser(XML_ParserCreate(nullptr), &XML_ParserFree);
  st.parser = parser.get();
  XML_SetUserData(parser.get(), &st);
  XML_SetStartElementHandler(parser.get(), on_start);
  std::vector<char> buf(1 << 16);
  while (true) {
    in.read(buf.data(), static_cast<std::streamsize>(buf.size()));
    const auto n = static_cast<int>(in.gcount());
    const bool last = n < static_cast<int>(buf.size());
    const XML_Status status = XML_Parse(parser.get(), buf.data(), n, last ? 1 : 0);
    if (status == XML_STATUS_SUSPENDED || (status == XML_STATUS_ERROR && XML_GetErrorCode(parser.get()) == XML_ERROR_ABORTED)) {
      return false;
    }
    if (status == XML_STATUS_ERROR) {
      throw MapLoadError("'" + file.string() + "' is not valid XML at line " +
                         std::to_string(XML_GetCurrentLineNumber(parser.get())) + ": " +
                         XML_ErrorString(XML_GetErrorCode(parser.get())));
    }
    if (!st.error.empty()) throw MapLoadError("'" + file.string() + "': " + st.error);
    if (last) return true;
  }
}

}  // namespace

SumoNet read_sumo_net(const std::filesystem::path& file) {
  ParseState st;
  parse_sumo_xml(file, "SUMO network", st);
  if (st.net.edges.empty()) throw MapLoadError("'" + file.string() + "' holds no SUMO edges: is it a .net.xml?");
  st.net.build_index();
  return std::move(st.net);
}

std::vector<SumoTlLogic> read_sumo_tl_logics(const std::filesystem::path& file) {
  ParseState st;
  parse_sumo_xml(file, "SUMO additional file", st);
  return std::move(st.net.tl_logics);
}

std::string read_sumo_net_version(const std::filesystem::path& file) {
  ParseState st;
  st.stop_at_net = true;
  parse_sumo_xml(file, "SUMO network", st);
  return st.net.version;
}

std::vector<SumoSignalPlan> sumo_signal_plans(const SumoNet& net, double min_all_red_s) {
  std::map<std::string, const SumoEdge*> edges;
  for (const auto& e : net.edges) edges[e.id] = &e;
  std::vector<SumoSignalPlan> out;
  for (const SumoTlLogic& logic : net.tl_logics) {
    if (logic.phases.empty()) continue;
    const std::size_t n = logic.phases.front().state.size();
    for (const auto& p : logic.phases) {
      if (p.state.size() != n) {
        throw MapLoadError("traffic light '" + logic.id + "' has phases with different numbers of links");
      }
    }
    SumoSignalPlan sp;
    sp.tls_id = logic.id;
    sp.program_id = logic.program_id;
    sp.links.assign(n, nullptr);
    for (const SumoConnection& c : net.connections) {
      if (c.tl == logic.id && c.link_index >= 0 && static_cast<std::size_t>(c.link_index) < n) sp.links[c.link_index] = &c;
    }
    SignalPlan& plan = sp.plan;
    plan.movements.resize(n);
    // Where each link is: its junction (the from edge's end) and its junction-internal index.
    std::vector<const SumoJunction*> junction_of(n, nullptr);
    std::vector<std::optional<std::size_t>> junction_link(n);
    for (std::size_t i = 0; i < n; ++i) {
      const SumoConnection* c = sp.links[i];
      if (c == nullptr) continue;
      const auto from = edges.find(c->from), to = edges.find(c->to);
      if (from == edges.end() || to == edges.end()) continue;
      junction_of[i] = net.junction(from->second->to);
      if (junction_of[i] == nullptr) continue;
      junction_link[i] = junction_link_index(c->via, junction_of[i]->id);
      const Point2 center = junction_of[i]->position;
      Movement& m = plan.movements[i];
      const auto& in_shape = from->second->lanes.empty() ? std::vector<Point2>{} : from->second->lanes.front().shape;
      const auto& out_shape = to->second->lanes.empty() ? std::vector<Point2>{} : to->second->lanes.front().shape;
      if (in_shape.size() >= 2) m.from = compass_side(center, in_shape[in_shape.size() - 2]);
      if (out_shape.size() >= 2) m.to = compass_side(center, out_shape[1]);
      m.turn = turn_of(c->dir);
    }
    plan.conflict.assign(n * n, 0);
    for (std::size_t a = 0; a < n; ++a) {
      for (std::size_t b = 0; b < n; ++b) {
        if (a == b || junction_of[a] == nullptr || junction_of[a] != junction_of[b] || !junction_link[a] || !junction_link[b]) continue;
        const auto& req = junction_of[a]->requests;
        const bool ab = *junction_link[a] < req.size() && bit(req[*junction_link[a]].foes, *junction_link[b]);
        const bool ba = *junction_link[b] < req.size() && bit(req[*junction_link[b]].foes, *junction_link[a]);
        plan.conflict[a * n + b] = plan.conflict[b * n + a] = (ab || ba) ? 1 : 0;
      }
    }
    plan.yellow_s = 0.0;
    plan.all_red_s = min_all_red_s;
    for (const SumoTlPhase& p : logic.phases) {
      const bool any_yellow = p.state.find_first_of("yY") != std::string::npos;
      const bool any_green = p.state.find_first_of("Gg") != std::string::npos;
      if (any_yellow) plan.yellow_s = std::max(plan.yellow_s, p.duration_s);
      if (!any_yellow && !any_green) plan.all_red_s = std::max(plan.all_red_s, p.duration_s);
      if (any_yellow || !any_green) continue;
      Phase phase;
      phase.green.assign(n, 0);
      for (std::size_t i = 0; i < n; ++i) phase.green[i] = p.state[i] == 'G' || p.state[i] == 'g' ? 1 : 0;
      phase.label = p.state;
      phase.min_green_s = std::min(p.duration_s, p.min_duration_s > 0 ? p.min_duration_s : 5.0);
      std::size_t index = plan.phases.size();
      for (std::size_t k = 0; k < plan.phases.size(); ++k) {
        if (plan.phases[k].green == phase.green) index = k;
      }
      if (index == plan.phases.size()) plan.phases.push_back(phase);
      plan.program.push_back({index, p.duration_s});
    }
    if (plan.yellow_s <= 0.0) plan.yellow_s = 3.0;
    if (!plan.program.empty()) out.push_back(std::move(sp));
  }
  return out;
}

}  // namespace corridor::maps
