#include "planner/experiments/analytical_graph.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <numeric>
#include <sstream>

#include "maps/errors.hpp"
#include "planner/experiments/builtin_graphs.hpp"

namespace corridor::planner {
namespace {

constexpr std::string_view kFormat = "corridor-analytical-graph";
constexpr int kVersion = 1;

struct InputEdge {
  std::uint32_t from;
  std::uint32_t to;
  double length_m;
  std::uint32_t index;  // position in the file: becomes the edge's way id, so reports can name it
};

[[noreturn]] void fail(const std::string& origin, const std::string& what) {
  throw GraphFileError(origin + ": " + what);
}

double finite_number(const nlohmann::json& j, const char* key, const std::string& where, const std::string& origin) {
  const auto it = j.find(key);
  if (it == j.end() || !it->is_number()) fail(origin, where + " needs a number \"" + key + "\"");
  const double v = it->get<double>();
  if (!std::isfinite(v)) fail(origin, where + ": \"" + key + "\" is not finite");
  return v;
}

std::string text(const nlohmann::json& j, const char* key, const std::string& where, const std::string& origin) {
  const auto it = j.find(key);
  if (it == j.end() || !it->is_string() || it->get<std::string>().empty()) {
    fail(origin, where + " needs a non-empty string \"" + key + "\"");
  }
  return it->get<std::string>();
}

}  // namespace

std::optional<NodeId> AnalyticalGraph::find(std::string_view node_name) const {
  const auto it = std::find(node_names.begin(), node_names.end(), node_name);
  if (it == node_names.end()) return std::nullopt;
  return NodeId{static_cast<std::uint32_t>(it - node_names.begin())};
}

namespace {

AnalyticalGraph parse(std::string_view json_text, const std::string& origin) {
  nlohmann::json doc;
  try {
    doc = nlohmann::json::parse(json_text);
  } catch (const nlohmann::json::exception& e) {  // a syntax error, or a number too large for a double
    fail(origin, std::string("not valid JSON (") + e.what() + ")");
  }
  if (!doc.is_object()) fail(origin, "the top level must be a JSON object");
  if (doc.value("format", std::string{}) != kFormat) {
    fail(origin, "\"format\" must be \"" + std::string(kFormat) + "\"");
  }
  if (!doc.contains("version") || !doc["version"].is_number_integer() || doc["version"].get<int>() != kVersion) {
    fail(origin, "unsupported \"version\" (this build reads version " + std::to_string(kVersion) + ")");
  }
  const double speed_kmh = finite_number(doc, "speed_kmh", "the graph", origin);
  if (!(speed_kmh > 0.0 && speed_kmh <= 400.0)) fail(origin, "\"speed_kmh\" must be in (0, 400]");

  const auto& nodes = doc.value("nodes", nlohmann::json::array());
  const auto& edges = doc.value("edges", nlohmann::json::array());
  if (!nodes.is_array() || nodes.size() < 2) fail(origin, "\"nodes\" must be an array of at least two nodes");
  if (!edges.is_array() || edges.empty()) fail(origin, "\"edges\" must be a non-empty array");

  std::map<std::string, std::uint32_t> index_of;
  std::vector<std::string> names;
  std::vector<double> xs;
  std::vector<double> ys;
  std::vector<std::uint8_t> signalized;
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    const auto& n = nodes[i];
    const std::string where = "node #" + std::to_string(i + 1);
    if (!n.is_object()) fail(origin, where + " must be an object");
    std::string id = text(n, "id", where, origin);
    if (!index_of.emplace(id, static_cast<std::uint32_t>(names.size())).second) {
      fail(origin, "node id \"" + id + "\" appears twice");
    }
    names.push_back(std::move(id));
    xs.push_back(finite_number(n, "x_km", where, origin) * 1000.0);
    ys.push_back(finite_number(n, "y_km", where, origin) * 1000.0);
    const auto sig = n.find("signalized");
    if (sig != n.end() && !sig->is_boolean()) fail(origin, where + ": \"signalized\" must be true or false");
    // The paper's model puts a signal at every intersection.
    signalized.push_back(sig == n.end() || sig->get<bool>() ? 1 : 0);
  }

  std::vector<InputEdge> directed;
  for (std::size_t i = 0; i < edges.size(); ++i) {
    const auto& e = edges[i];
    const std::string where = "edge #" + std::to_string(i + 1);
    if (!e.is_object()) fail(origin, where + " must be an object");
    const std::string from = text(e, "from", where, origin);
    const std::string to = text(e, "to", where, origin);
    const auto f = index_of.find(from);
    const auto t = index_of.find(to);
    if (f == index_of.end()) fail(origin, where + " starts at unknown node \"" + from + "\"");
    if (t == index_of.end()) fail(origin, where + " ends at unknown node \"" + to + "\"");
    if (f->second == t->second) fail(origin, where + " is a loop at \"" + from + "\"");
    const double length_km = finite_number(e, "length_km", where, origin);
    if (!(length_km > 0.0)) fail(origin, where + ": \"length_km\" must be positive");
    const auto ow = e.find("oneway");
    if (ow != e.end() && !ow->is_boolean()) fail(origin, where + ": \"oneway\" must be true or false");
    const auto idx = static_cast<std::uint32_t>(i);
    directed.push_back({f->second, t->second, length_km * 1000.0, idx});
    if (ow == e.end() || !ow->get<bool>()) directed.push_back({t->second, f->second, length_km * 1000.0, idx});
  }
  std::stable_sort(directed.begin(), directed.end(), [](const InputEdge& a, const InputEdge& b) { return a.from < b.from; });

  maps::RoadGraphData d;
  d.origin = {47.0, 9.5};  // any valid point: only the local frame matters
  d.node_x_m = xs;
  d.node_y_m = ys;
  d.node_osm_id.resize(names.size());
  for (std::size_t i = 0; i < names.size(); ++i) d.node_osm_id[i] = OsmNodeId{static_cast<std::int64_t>(i + 1)};
  d.node_signalized = signalized;
  d.first_out.assign(names.size() + 1, 0);
  d.geometry_first.push_back(0);
  for (const InputEdge& e : directed) {
    ++d.first_out[e.from + 1];
    d.edge_tail.push_back(NodeId{e.from});
    d.edge_head.push_back(NodeId{e.to});
    d.edge_length_m.push_back(e.length_m);
    d.edge_speed_mps.push_back(static_cast<float>(speed_kmh / 3.6));
    d.edge_osm_way.push_back(OsmWayId{e.index + 1});
    d.edge_class.push_back(maps::RoadClass::primary);
    d.geometry.push_back({xs[e.from], ys[e.from]});
    d.geometry.push_back({xs[e.to], ys[e.to]});
    d.geometry_first.push_back(static_cast<std::uint32_t>(d.geometry.size()));
  }
  std::partial_sum(d.first_out.begin(), d.first_out.end(), d.first_out.begin());
  d.edge_twin.assign(directed.size(), kInvalidEdge);
  for (std::size_t a = 0; a < directed.size(); ++a) {
    for (std::size_t b = 0; b < directed.size(); ++b) {
      if (a != b && directed[a].index == directed[b].index) d.edge_twin[a] = EdgeId{static_cast<std::uint32_t>(b)};
    }
  }
  maps::build_reverse_adjacency(d);
  // The seed's hand-made graphs are abstract links with times, not streets: no turn has a cost or
  // a rule, as in the paper.
  d.turns_in_edges = {1};

  const std::string source = text(doc, "source", "the graph", origin);
  const std::string destination = text(doc, "destination", "the graph", origin);
  if (!index_of.contains(source)) fail(origin, "\"source\" names unknown node \"" + source + "\"");
  if (!index_of.contains(destination)) fail(origin, "\"destination\" names unknown node \"" + destination + "\"");
  if (source == destination) fail(origin, "\"source\" and \"destination\" must differ");

  return AnalyticalGraph{doc.value("name", std::string{}),
                         doc.value("description", std::string{}),
                         maps::RoadGraph(std::move(d)),
                         std::move(names),
                         NodeId{index_of.at(source)},
                         NodeId{index_of.at(destination)}};
}

}  // namespace

AnalyticalGraph parse_analytical_graph(std::string_view json_text, const std::string& origin) {
  try {
    return parse(json_text, origin);
  } catch (const nlohmann::json::exception& e) {
    // A field of the wrong type that the checks above read with a default.
    throw GraphFileError(origin + ": " + e.what());
  } catch (const maps::MapError& e) {
    throw GraphFileError(origin + ": " + e.what());
  }
}

AnalyticalGraph load_analytical_graph(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw GraphFileError(file.string() + ": cannot open the graph file");
  std::ostringstream text;
  text << in.rdbuf();
  return parse_analytical_graph(text.str(), file.string());
}

std::optional<AnalyticalGraph> builtin_analytical_graph(std::string_view name) {
  const std::string_view text = builtin_graph_json(name);
  if (text.empty()) return std::nullopt;
  return parse_analytical_graph(text, "built-in graph '" + std::string(name) + "'");
}

}  // namespace corridor::planner
