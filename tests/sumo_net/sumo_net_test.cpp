#include "maps/sumo_net.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <set>

#include "maps/errors.hpp"
#include "preemption/phase_selection.hpp"

namespace corridor::maps {
namespace {

// Built by the CTest fixture with netconvert from ../shared/data/osm/monaco.osm.gz.
const SumoNet& monaco() {
  static const SumoNet net = read_sumo_net(CORRIDOR_MONACO_NET);
  return net;
}

TEST(SumoNet, ReadsEdgesJunctionsConnectionsAndTrafficLights) {
  const SumoNet& net = monaco();
  EXPECT_GT(net.edges.size(), 500u);
  EXPECT_GT(net.junctions.size(), 200u);
  EXPECT_GT(net.connections.size(), 500u);
  ASSERT_GE(net.tl_logics.size(), 3u);
  for (const auto& logic : net.tl_logics) {
    EXPECT_FALSE(logic.phases.empty()) << logic.id;
    for (const auto& p : logic.phases) {
      EXPECT_GT(p.duration_s, 0.0);
      EXPECT_EQ(p.state.size(), logic.phases.front().state.size());
    }
  }
  const SumoJunction* j = net.junction(net.tl_logics.front().id);
  ASSERT_NE(j, nullptr);
  EXPECT_EQ(j->type, "traffic_light");
  EXPECT_FALSE(j->requests.empty());
  for (const auto& e : net.edges) {
    for (const auto& lane : e.lanes) {
      ASSERT_GE(lane.shape.size(), 2u) << lane.id;
      ASSERT_GT(lane.length_m, 0.0) << lane.id;
    }
  }
}

TEST(SumoNet, EveryLinkOfEveryProgramHasItsConnection) {
  const auto plans = sumo_signal_plans(monaco());
  ASSERT_EQ(plans.size(), monaco().tl_logics.size());
  for (const auto& sp : plans) {
    ASSERT_EQ(sp.links.size(), sp.plan.movements.size());
    for (std::size_t i = 0; i < sp.links.size(); ++i) {
      ASSERT_NE(sp.links[i], nullptr) << sp.tls_id << " link " << i;
      EXPECT_EQ(sp.links[i]->link_index, static_cast<int>(i));
      EXPECT_EQ(sp.links[i]->tl, sp.tls_id);
      EXPECT_FALSE(sp.links[i]->via.empty());
    }
    EXPECT_FALSE(sp.plan.program.empty());
    EXPECT_GT(sp.plan.yellow_s, 0.0);
  }
}

// The parsed conflict relation against SUMO's own programs: links SUMO shows with priority green
// ('G') together must never be foes. A wrong link mapping or bit order breaks this.
TEST(SumoNet, PriorityGreensOfSumoPhasesNeverConflict) {
  std::size_t pairs_checked = 0, conflicts_found = 0;
  for (const auto& sp : sumo_signal_plans(monaco())) {
    const std::size_t n = sp.plan.movements.size();
    for (std::size_t a = 0; a < n; ++a) {
      EXPECT_FALSE(sp.plan.conflicts(a, a));
      for (std::size_t b = 0; b < n; ++b) {
        EXPECT_EQ(sp.plan.conflicts(a, b), sp.plan.conflicts(b, a));
        conflicts_found += sp.plan.conflicts(a, b) ? 1 : 0;
      }
    }
    for (const auto& logic : monaco().tl_logics) {
      if (logic.id != sp.tls_id) continue;
      for (const auto& phase : logic.phases) {
        for (std::size_t a = 0; a < n; ++a) {
          for (std::size_t b = a + 1; b < n; ++b) {
            if (phase.state[a] == 'G' && phase.state[b] == 'G') {
              ++pairs_checked;
              EXPECT_FALSE(sp.plan.conflicts(a, b)) << sp.tls_id << " " << phase.state << " links " << a << "," << b;
            }
          }
        }
      }
    }
  }
  EXPECT_GT(pairs_checked, 20u);
  EXPECT_GT(conflicts_found, 20u);  // the relation is not empty either
}

// For every link of every Monaco signal, preemption finds a phase that serves it and is safe
// under the strict conflict relation (SUMO's permissive 'g' phases are not, so some are built).
TEST(SumoNet, PreemptionPhaseForEveryLinkIsSafe) {
  std::size_t synthesized = 0, decisions = 0;
  for (const auto& sp : sumo_signal_plans(monaco())) {
    for (std::size_t link = 0; link < sp.plan.movements.size(); ++link) {
      for (auto level : {preemption::CongestionLevel::low, preemption::CongestionLevel::high}) {
        for (std::size_t current = 0; current < sp.plan.phases.size(); ++current) {
          const auto d = preemption::select_phase(sp.plan, link, current, level);
          ++decisions;
          EXPECT_TRUE(d.phase.serves(link));
          EXPECT_TRUE(sp.plan.phase_is_safe(d.phase)) << sp.tls_id << " link " << link;
          synthesized += d.index ? 0 : 1;
        }
      }
    }
  }
  EXPECT_GT(decisions, 50u);
  std::cout << decisions << " decisions, " << synthesized << " synthesized phases\n";
}

TEST(SumoNet, BadFilesAreClearErrors) {
  EXPECT_THROW((void)read_sumo_net("/no/such/net.net.xml"), MapLoadError);
  const auto path = std::filesystem::temp_directory_path() / "corridor-broken.net.xml";
  std::ofstream(path) << "<net>\n<edge id=\"a\">\n<lane id=\"a_0\" shape=\"0,0 1,1\"/>\n</net>\n";
  try {
    (void)read_sumo_net(path);
    FAIL();
  } catch (const MapLoadError& e) {
    EXPECT_NE(std::string(e.what()).find("line"), std::string::npos) << e.what();
  }
  std::ofstream(path) << "<osm version=\"0.6\"></osm>\n";
  EXPECT_THROW((void)read_sumo_net(path), MapLoadError);
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace corridor::maps

#include "maps/sumo_graph.hpp"

namespace corridor::maps {
namespace {

TEST(SumoGraph, EveryGraphEdgeIsASumoConnectionSoTurnRulesHold) {
  const SumoNet& net = monaco();
  const SumoGraph g = build_sumo_graph(net);
  std::set<std::pair<std::string, std::string>> connected;
  for (const auto& c : net.connections) connected.emplace(c.from, c.to);
  std::size_t entry_arcs = 0;
  for (EdgeId e : g.graph.edges()) {
    const std::string& from = g.sumo_edge_of_node[g.graph.tail(e).index()];
    const std::string& onto = g.sumo_edge_of_arc[e.index()];
    EXPECT_EQ(g.sumo_edge_of_node[g.graph.head(e).index()], onto);
    if (from == onto) {
      ++entry_arcs;  // the entry node of an edge nothing leads into
      continue;
    }
    EXPECT_TRUE(connected.contains({from, onto})) << from << " -> " << onto << " is not a SUMO connection";
  }
  EXPECT_GT(g.graph.edge_count(), 500u);
  EXPECT_LT(entry_arcs, g.graph.edge_count() / 5);
  for (const auto& [sumo_edge, arcs] : g.arcs_onto) {
    ASSERT_FALSE(arcs.empty());
    for (EdgeId arc : arcs) EXPECT_EQ(g.graph.head(arc), g.stop_line.at(sumo_edge));
  }
}

TEST(SumoGraph, SignalPlansSitOnTheStopLinesTheirLightControlsWithExactMovements) {
  const SumoNet& net = monaco();
  const SumoGraph g = build_sumo_graph(net);
  const auto sumo_plans = sumo_signal_plans(net);
  std::unordered_map<NodeId, std::size_t> tls_of;
  const auto plans = plans_by_node(g, net, sumo_plans, &tls_of);
  ASSERT_FALSE(plans.empty());
  for (const auto& [node, plan] : plans) {
    EXPECT_EQ(plan.node, node);
    EXPECT_TRUE(g.graph.signalized(node));
    const SumoSignalPlan& sp = sumo_plans.at(tls_of.at(node));
    ASSERT_EQ(plan.movement_edge.size(), sp.links.size());
    bool from_here = false;
    for (std::size_t k = 0; k < sp.links.size(); ++k) {
      if (sp.links[k] == nullptr || !plan.movement_edge[k].valid()) continue;
      const EdgeId arc = plan.movement_edge[k];
      EXPECT_EQ(g.sumo_edge_of_node[g.graph.tail(arc).index()], sp.links[k]->from);
      EXPECT_EQ(g.sumo_edge_of_arc[arc.index()], sp.links[k]->to);
      from_here = from_here || g.graph.tail(arc) == node;
    }
    EXPECT_TRUE(from_here) << "the light of node " << node.v << " controls no link from its stop line";
  }
}

TEST(SumoGraph, LinksFromOneLaneAreEachOthersLaneMates) {
  const SumoNet& net = monaco();
  const SumoGraph g = build_sumo_graph(net);
  const auto sumo_plans = sumo_signal_plans(net);
  std::unordered_map<NodeId, std::size_t> tls_of;
  const auto plans = plans_by_node(g, net, sumo_plans, &tls_of);
  std::size_t shared = 0;
  for (const auto& [node, plan] : plans) {
    const SumoSignalPlan& sp = sumo_plans.at(tls_of.at(node));
    ASSERT_EQ(plan.lane_mates.size(), sp.links.size());
    for (std::size_t k = 0; k < sp.links.size(); ++k) {
      for (std::size_t j = 0; j < sp.links.size(); ++j) {
        const bool same_lane = j != k && sp.links[k] != nullptr && sp.links[j] != nullptr && sp.links[k]->from == sp.links[j]->from &&
                               sp.links[k]->from_lane == sp.links[j]->from_lane;
        const auto& mates = plan.lane_mates[k];
        EXPECT_EQ(std::find(mates.begin(), mates.end(), j) != mates.end(), same_lane) << "links " << k << " and " << j;
        shared += same_lane ? 1 : 0;
      }
    }
  }
  EXPECT_GT(shared, 0u);  // Monaco has approaches whose one lane serves two movements
}

}  // namespace
}  // namespace corridor::maps

#include "planner/cost_overlay.hpp"
#include "planner/one_to_one_search.hpp"
#include "planner/travel_cost.hpp"

namespace corridor::maps {
namespace {

// tests/data/lane_permissions: AB is a bus lane, AE -> EC a connection only buses may take.
const SumoNet& permissions_net() {
  static const SumoNet net = read_sumo_net(CORRIDOR_PERMISSIONS_NET);
  return net;
}

std::vector<std::string> shortest_route(const SumoGraph& g, const std::string& from, const std::string& to) {
  const planner::CostOverlay overlay(g.graph);
  const planner::TravelCost cost(g.graph, overlay, {});
  std::vector<planner::EdgePoint> starts, goals;
  for (EdgeId e : g.arcs(from)) starts.push_back({e, 0.0});
  for (EdgeId e : g.arcs(to)) goals.push_back({e, g.graph.length_m(e)});
  planner::OneToOneSearch search;
  const planner::Route r = search.run(planner::SearchSpace(cost, starts, goals), true);
  std::vector<std::string> ids;
  for (EdgeId e : r.edges) ids.push_back(g.sumo_edge_of_arc[e.index()]);
  return ids;
}

bool has_arc(const SumoGraph& g, const std::string& from, const std::string& onto) {
  for (EdgeId e : g.arcs(onto)) {
    if (g.sumo_edge_of_node[g.graph.tail(e).index()] == from) return true;
  }
  return false;
}

TEST(SumoPermissions, LanesAndConnectionsAdmitTheClassesTheyAllow) {
  const SumoNet& net = permissions_net();
  const SumoEdge* ab = net.edge("AB");
  ASSERT_NE(ab, nullptr);
  EXPECT_TRUE(ab->admits(*sumo_class_bit("bus")));
  EXPECT_FALSE(ab->admits(*sumo_class_bit("emergency")));
  EXPECT_TRUE(net.edge("AD")->admits(*sumo_class_bit("emergency")));
  const auto connection = [&](const std::string& from, const std::string& to) {
    for (const auto& c : net.connections) {
      if (c.from == from && c.to == to) return &c;
    }
    return static_cast<const SumoConnection*>(nullptr);
  };
  ASSERT_NE(connection("AE", "EC"), nullptr);
  EXPECT_TRUE(net.admits(*connection("AE", "EC"), *sumo_class_bit("bus")));
  EXPECT_FALSE(net.admits(*connection("AE", "EC"), *sumo_class_bit("emergency")));
  EXPECT_TRUE(net.admits(*connection("AD", "DC"), *sumo_class_bit("emergency")));
  // The internal lane alone carries the rule too, where a connection has no attribute of its own.
  SumoConnection bare = *connection("AE", "EC");
  bare.allowed.reset();
  EXPECT_FALSE(net.admits(bare, *sumo_class_bit("emergency")));
}

TEST(SumoPermissions, AnEmergencyVehiclesGraphAvoidsTheBusLaneAndTheBusOnlyTurn) {
  const SumoGraph ev = build_sumo_graph(permissions_net(), "emergency");
  EXPECT_TRUE(ev.arcs("AB").empty());
  EXPECT_FALSE(has_arc(ev, "AE", "EC"));
  EXPECT_TRUE(has_arc(ev, "AD", "DC"));
  EXPECT_EQ(shortest_route(ev, "SA", "CG"), (std::vector<std::string>{"SA", "AD", "DC", "CG"}));
  const SumoGraph bus = build_sumo_graph(permissions_net(), "bus");
  EXPECT_TRUE(has_arc(bus, "SA", "AB"));
  EXPECT_TRUE(has_arc(bus, "AE", "EC"));
  EXPECT_EQ(shortest_route(bus, "SA", "CG"), (std::vector<std::string>{"SA", "AB", "BC", "CG"}));
  EXPECT_THROW((void)build_sumo_graph(permissions_net(), "hovercraft"), MapLoadError);
}

TEST(SumoPermissions, AllowAndDisallowAsSumoReadsThem) {
  const SumoClasses bus = *sumo_class_bit("bus"), ev = *sumo_class_bit("emergency"), car = *sumo_class_bit("passenger");
  EXPECT_EQ(parse_sumo_permissions("", ""), kAllSumoClasses);
  EXPECT_EQ(parse_sumo_permissions("bus emergency", ""), bus | ev);
  EXPECT_EQ(parse_sumo_permissions("", "passenger bus") & (bus | car), 0u);
  EXPECT_NE(parse_sumo_permissions("", "passenger bus") & ev, 0u);
  EXPECT_EQ(parse_sumo_permissions("all", ""), kAllSumoClasses);
  EXPECT_EQ(parse_sumo_permissions("", "all"), 0u);
  // A class a newer SUMO has (and this one does not) admits none of this SUMO's vehicles.
  EXPECT_EQ(parse_sumo_permissions("scooter", ""), 0u);
  EXPECT_EQ(sumo_class_names(bus | ev), "emergency bus");
}

}  // namespace
}  // namespace corridor::maps
