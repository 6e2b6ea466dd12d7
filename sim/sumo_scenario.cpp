#include "sim/sumo_scenario.hpp"

#include <memory>

namespace corridor::sim {

std::unique_ptr<SumoScenario> load_sumo_scenario(const ScenarioNet& scenario_net, const std::string& ev_vclass) {
  maps::SumoNet net = maps::read_sumo_net(scenario_net.net);
  if (scenario_net.config) {
    for (const auto& file : scenario_net.config->additional_files) {
      for (maps::SumoTlLogic& logic : maps::read_sumo_tl_logics(file)) {
        std::erase_if(net.tl_logics, [&](const maps::SumoTlLogic& l) { return l.id == logic.id; });
        net.tl_logics.push_back(std::move(logic));
      }
    }
  }
  maps::SumoGraph graph = maps::build_sumo_graph(net, ev_vclass);
  auto s = std::unique_ptr<SumoScenario>(new SumoScenario{scenario_net.name, ev_vclass, scenario_net.dir, scenario_net.net,
                                                          std::move(net), std::move(graph), {}, {}, {}, {}, {}, {}, {},
                                                          scenario_net.config,
                                                          SumoOptionCatalog::from_sumo("sumo", scenario_net.dir)});
  s->sumo_plans = maps::sumo_signal_plans(s->net);
  // The same signals the server keys a SUMO net's lights by.
  std::unordered_map<NodeId, std::size_t> tls_of;
  maps::SignalMap signals = maps::sumo_signal_map(s->graph, s->net, s->sumo_plans, &tls_of);
  for (const auto& [node, index] : tls_of) s->sumo_plan_of[node] = &s->sumo_plans[index];
  for (const auto& logic : s->net.tl_logics) {
    s->tls_phases[logic.id] = logic.phases;
    if (logic.type == "actuated" || logic.type == "delay_based") s->actuated_tls.insert(logic.id);
  }
  s->plans = std::move(signals.plans);
  s->signal_plans = std::move(signals.signals);
  s->signal_node = std::move(signals.signal_of);
  return s;
}

}  // namespace corridor::sim
