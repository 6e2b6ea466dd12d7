// The small hand-made networks of the analytical experiments (the seed paper's Fig. 4), read from
// versioned JSON files into an ordinary RoadGraph, with their node names kept for reports.
#pragma once

#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "maps/road_graph.hpp"

namespace corridor::planner {

// The graph file is unreadable, not valid JSON, of another format or version, or inconsistent.
class GraphFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct AnalyticalGraph {
  std::string name;
  std::string description;
  maps::RoadGraph graph;
  std::vector<std::string> node_names;  // by NodeId
  NodeId source;                        // the default trip of Figs. 5, 6, 8 and 9
  NodeId destination;

  [[nodiscard]] const std::string& name_of(NodeId v) const { return node_names[v.index()]; }
  [[nodiscard]] std::optional<NodeId> find(std::string_view node_name) const;
};

// `origin` names the text in error messages (a file path, or "built-in graph 'simple'").
AnalyticalGraph parse_analytical_graph(std::string_view json_text, const std::string& origin);
AnalyticalGraph load_analytical_graph(const std::filesystem::path& file);

// "simple" or "complex", compiled in from planner/experiments/graphs/. Empty for any other name.
std::optional<AnalyticalGraph> builtin_analytical_graph(std::string_view name);

}  // namespace corridor::planner
