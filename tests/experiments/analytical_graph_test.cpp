#include "planner/experiments/analytical_graph.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

namespace corridor::planner {
namespace {

TEST(AnalyticalGraph, BuiltinSimpleGraphHasOneDecisionPointAndTwoCorridors) {
  const auto g = builtin_analytical_graph("simple");
  ASSERT_TRUE(g.has_value());
  EXPECT_EQ(g->graph.node_count(), 6u);
  EXPECT_EQ(g->graph.edge_count(), 12u);  // six two-way roads
  EXPECT_EQ(g->name_of(g->source), "a");
  EXPECT_EQ(g->name_of(g->destination), "d");
  const NodeId b = *g->find("b");
  EXPECT_EQ(g->graph.out_edges(b).size(), 3u);  // back to a, or one of the two corridors
  for (EdgeId e : g->graph.edges()) {
    EXPECT_TRUE(g->graph.twin(e).valid());
    EXPECT_EQ(g->graph.twin(g->graph.twin(e)), e);
    EXPECT_NEAR(g->graph.speed_mps(e), 120.0 / 3.6, 1e-5);
  }
}

TEST(AnalyticalGraph, BuiltinComplexGraphHasThirteenNodesAToM) {
  const auto g = builtin_analytical_graph("complex");
  ASSERT_TRUE(g.has_value());
  EXPECT_EQ(g->graph.node_count(), 13u);
  EXPECT_EQ(g->graph.edge_count(), 46u);
  EXPECT_EQ(g->name_of(NodeId{0}), "A");
  EXPECT_EQ(g->name_of(NodeId{12}), "M");
  for (NodeId v : g->graph.nodes()) EXPECT_TRUE(g->graph.signalized(v));
  // Lengths are kept as given, not recomputed from the coordinates.
  const NodeId a = *g->find("A");
  const NodeId c = *g->find("C");
  bool found = false;
  for (EdgeId e : g->graph.out_edges(a)) {
    if (g->graph.head(e) == c) {
      EXPECT_DOUBLE_EQ(g->graph.length_m(e), 3300.0);
      found = true;
    }
  }
  EXPECT_TRUE(found);
  EXPECT_FALSE(builtin_analytical_graph("grid").has_value());
}

TEST(AnalyticalGraph, OnewayEdgesHaveNoTwinAndNodesMayBeUnsignalized) {
  const auto g = parse_analytical_graph(R"({"format":"corridor-analytical-graph","version":1,"name":"t","speed_kmh":60,
    "source":"x","destination":"y",
    "nodes":[{"id":"x","x_km":0,"y_km":0,"signalized":false},{"id":"y","x_km":1,"y_km":0}],
    "edges":[{"from":"x","to":"y","length_km":1.5,"oneway":true},{"from":"y","to":"x","length_km":2,"oneway":true}]})",
                                        "test");
  EXPECT_EQ(g.graph.edge_count(), 2u);
  EXPECT_FALSE(g.graph.twin(EdgeId{0}).valid());
  EXPECT_FALSE(g.graph.signalized(*g.find("x")));
  EXPECT_TRUE(g.graph.signalized(*g.find("y")));
  EXPECT_NEAR(g.graph.speed_mps(EdgeId{0}), 60.0 / 3.6, 1e-5);
}

void expect_error(const std::string& json, const std::string& fragment) {
  try {
    parse_analytical_graph(json, "g.json");
    ADD_FAILURE() << "accepted: " << json;
  } catch (const GraphFileError& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("g.json"), std::string::npos) << e.what();
  }
}

TEST(AnalyticalGraph, RejectsBadFilesWithMessagesThatNameTheProblem) {
  const std::string head = R"("format":"corridor-analytical-graph","version":1,"speed_kmh":120,)";
  const std::string nodes = R"("nodes":[{"id":"a","x_km":0,"y_km":0},{"id":"b","x_km":1,"y_km":0}])";
  expect_error("{", "not valid JSON");
  expect_error("[]", "JSON object");
  expect_error(R"({"format":"other","version":1})", "format");
  expect_error(R"({"format":"corridor-analytical-graph","version":7})", "version");
  expect_error("{" + head + nodes + R"(,"edges":[{"from":"a","to":"z","length_km":1}],"source":"a","destination":"b"})",
               "unknown node \"z\"");
  expect_error("{" + head + nodes + R"(,"edges":[{"from":"a","to":"b","length_km":-1}],"source":"a","destination":"b"})",
               "length_km");
  expect_error("{" + head + nodes + R"(,"edges":[{"from":"a","to":"b","length_km":"1"}],"source":"a","destination":"b"})",
               "length_km");
  expect_error("{" + head + nodes + R"(,"edges":[{"from":"a","to":"a","length_km":1}],"source":"a","destination":"b"})",
               "loop");
  expect_error("{" + head + nodes + R"(,"edges":[{"from":"a","to":"b","length_km":1}],"source":"a","destination":"q"})",
               "destination");
  expect_error("{" + head + R"("nodes":[{"id":"a","x_km":0,"y_km":0},{"id":"a","x_km":1,"y_km":0}],)" +
                   R"("edges":[{"from":"a","to":"a","length_km":1}],"source":"a","destination":"a"})",
               "appears twice");
  expect_error("{" + head + nodes + R"(,"edges":[{"from":"a","to":"b","length_km":1}],"source":"a","destination":"b","name":5})",
               "string");
}

TEST(AnalyticalGraph, LoadsTheVersionedFilesOfTheRepository) {
  const std::filesystem::path dir = std::filesystem::path(CORRIDOR_SOURCE_DIR) / "planner" / "experiments" / "graphs";
  for (const char* name : {"simple", "complex"}) {
    const auto from_file = load_analytical_graph(dir / (std::string(name) + ".json"));
    const auto builtin = builtin_analytical_graph(name);
    ASSERT_TRUE(builtin.has_value());
    EXPECT_EQ(from_file.graph.data().edge_length_m, builtin->graph.data().edge_length_m) << name;
  }
  EXPECT_THROW(load_analytical_graph(dir / "missing.json"), GraphFileError);
}

}  // namespace
}  // namespace corridor::planner
