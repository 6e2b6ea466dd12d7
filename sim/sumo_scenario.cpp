#include "sim/sumo_scenario.hpp"

#include <memory>

namespace corridor::sim {

std::unique_ptr<SumoScenario> load_sumo_scenario(const std::string& name, const std::filesystem::path& dir,
                                                 const std::filesystem::path& net_file) {
  maps::SumoNet net = maps::read_sumo_net(net_file);
  maps::SumoGraph graph = maps::build_sumo_graph(net);
  auto s = std::unique_ptr<SumoScenario>(new SumoScenario{name, dir, net_file, std::move(net), std::move(graph), {}, {}, {}, {}});
  s->sumo_plans = maps::sumo_signal_plans(s->net);
  std::unordered_map<NodeId, std::size_t> tls_of;
  s->plans = maps::plans_by_node(s->graph, s->net, s->sumo_plans, &tls_of);
  for (const auto& [node, index] : tls_of) s->sumo_plan_of[node] = &s->sumo_plans[index];
  for (const auto& logic : s->net.tl_logics) s->tls_phases[logic.id] = logic.phases;
  return s;
}

}  // namespace corridor::sim
