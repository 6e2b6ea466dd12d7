// Random signal plans for property tests: NEMA plans with random legs and timings, and arbitrary
// plans with a random conflict relation whose phases are random maximal compatible sets.
#pragma once

#include <random>

#include "maps/signal_plan.hpp"

namespace corridor::preemption::testing {

inline maps::SignalPlan random_plan(std::mt19937_64& rng, NodeId node) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  if (unit(rng) < 0.5) {
    maps::NemaTiming t;
    t.left_green_s = 4 + 10 * unit(rng);
    t.through_green_s = 8 + 30 * unit(rng);
    t.min_green_s = 3 + 5 * unit(rng);
    t.yellow_s = 2.5 + 2 * unit(rng);
    t.all_red_s = 0.5 + 2.5 * unit(rng);
    std::uint8_t legs = 0;
    while (__builtin_popcount(legs) < 3) legs |= static_cast<std::uint8_t>(1u << (rng() % 4));
    return maps::make_nema_plan(node, legs, t);
  }
  maps::SignalPlan plan;
  plan.node = node;
  plan.yellow_s = 2.5 + 2 * unit(rng);
  plan.all_red_s = 0.5 + 2.5 * unit(rng);
  const std::size_t n = 3 + rng() % 10;
  for (std::size_t m = 0; m < n; ++m) {
    plan.movements.push_back({static_cast<maps::Compass>(rng() % 4), static_cast<maps::Compass>(rng() % 4),
                              static_cast<maps::Turn>(rng() % 3), 0});
  }
  plan.conflict.assign(n * n, 0);
  for (std::size_t a = 0; a < n; ++a) {
    for (std::size_t b = a + 1; b < n; ++b) {
      const std::uint8_t c = unit(rng) < 0.5 ? 1 : 0;
      plan.conflict[a * n + b] = plan.conflict[b * n + a] = c;
    }
  }
  // Phases: grow a random compatible set from every movement not yet served.
  std::vector<std::uint8_t> served(n, 0);
  for (std::size_t seed = 0; seed < n; ++seed) {
    if (served[seed]) continue;
    maps::Phase phase;
    phase.label = "P" + std::to_string(plan.phases.size());
    phase.min_green_s = 3 + 5 * unit(rng);
    phase.green.assign(n, 0);
    phase.green[seed] = 1;
    std::vector<std::size_t> order(n);
    for (std::size_t i = 0; i < n; ++i) order[i] = i;
    std::shuffle(order.begin(), order.end(), rng);
    for (std::size_t m : order) {
      bool ok = true;
      for (std::size_t g = 0; g < n; ++g) ok = ok && !(phase.green[g] && plan.conflicts(g, m));
      if (ok) phase.green[m] = 1;
    }
    for (std::size_t m = 0; m < n; ++m) served[m] = served[m] || phase.green[m];
    plan.program.push_back({plan.phases.size(), 5 + 30 * unit(rng)});
    plan.phases.push_back(std::move(phase));
  }
  return plan;
}

}  // namespace corridor::preemption::testing
