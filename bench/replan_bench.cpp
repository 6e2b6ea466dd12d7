#include "bench/replan_bench.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <numeric>
#include <optional>
#include <chrono>
#include <cmath>
#include <random>
#include <stdexcept>
#include <unordered_set>

#include "maps/progress.hpp"
#include "planner/cch_metric.hpp"
#include "planner/cch_topology.hpp"
#include "planner/settled_replan.hpp"
#include "planner/cost_overlay.hpp"
#include "planner/dstar_lite.hpp"
#include "planner/one_to_one_search.hpp"

namespace corridor::bench {
namespace {

using planner::EdgePoint;
using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

bool costs_differ(double a, double b) {
  if (a >= planner::kInfCost || b >= planner::kInfCost) return a != b;
  return std::abs(a - b) > 1e-9 * std::max({1.0, std::abs(a), std::abs(b)});
}

// Where the vehicle is after driving `seconds` along `route` under the current costs, or nullopt
// when it reaches the goal first.
std::optional<EdgePoint> drive(const planner::TravelCost& cost, const planner::Route& route, double seconds) {
  const auto& g = cost.graph();
  double left = seconds;
  for (std::size_t i = 0; i < route.edges.size(); ++i) {
    const EdgeId e = route.edges[i];
    const double from = i == 0 ? route.start.offset_m : 0.0;
    const double to = i + 1 == route.edges.size() ? route.goal.offset_m : g.length_m(e);
    // The turn onto e and the crossing of its tail, then e itself, as the cost model charges them.
    const double before_edge =
        i == 0 ? 0.0 : planner::add_cost(cost.turn_onto(route.point_on(i - 1, 0.0).vertex(), e).first, cost.node_delay_s(g.tail(e)));
    if (left <= before_edge) return route.point_on(i, from);
    left -= before_edge;
    const double t = cost.partial_time_s(e, from, to);
    if (left < t) return route.point_on(i, from + (left / t) * (to - from));  // as the cost model: delay spread
    left -= t;
  }
  return std::nullopt;
}

class UpdateGenerator {
 public:
  UpdateGenerator(const maps::RoadGraph& graph, const ReplanBenchConfig& config, std::mt19937_64& rng)
      : graph_(graph), config_(config), rng_(rng) {}

  // Picks `count` edges: some ahead on the route, some next to it, the rest anywhere.
  std::vector<EdgeId> pick(const planner::Route& route) {
    std::vector<EdgeId> out;
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    std::uniform_int_distribution<std::uint32_t> any_edge(0, static_cast<std::uint32_t>(graph_.edge_count() - 1));
    for (std::uint32_t i = 0; i < config_.updates_per_batch; ++i) {
      const double r = unit(rng_);
      EdgeId e{any_edge(rng_)};
      if (r < config_.on_route_fraction && !route.edges.empty()) {
        e = route.edges[std::uniform_int_distribution<std::size_t>(0, route.edges.size() - 1)(rng_)];
      } else if (r < config_.on_route_fraction + config_.near_route_fraction && !route.nodes.empty()) {
        const NodeId n = route.nodes[std::uniform_int_distribution<std::size_t>(0, route.nodes.size() - 1)(rng_)];
        const auto outs = graph_.out_edges(n);
        const auto ins = graph_.in_edges(n);
        const std::size_t k = std::uniform_int_distribution<std::size_t>(0, outs.size() + ins.size() - 1)(rng_);
        e = k < outs.size() ? EdgeId{(*outs.begin()).v + static_cast<std::uint32_t>(k)} : ins[k - outs.size()];
      }
      out.push_back(e);
    }
    return out;
  }

  // Applies one update to `e`: slower (congestion, queues, rarely a closure) or, for an edge that is
  // congested, faster (congestion clearing, partly or fully). Returns the edge actually changed.
  EdgeId apply(EdgeId e, planner::CostOverlay& overlay) {
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    const double r = unit(rng_);
    if (r < config_.clearing_fraction && !congested_.empty()) {
      const std::size_t i = std::uniform_int_distribution<std::size_t>(0, congested_.size() - 1)(rng_);
      e = congested_[i];
      if (unit(rng_) < 0.5) {
        overlay.reset_edge(e);
        congested_[i] = congested_.back();
        congested_.pop_back();
      } else {
        const planner::EdgeCondition c = overlay.edge(e);
        const double factor = std::isfinite(c.congestion_factor) ? 1.0 + (c.congestion_factor - 1.0) * 0.5 : 2.0;
        overlay.set_edge(e, {factor, c.queue_delay_s * 0.5});
      }
      return e;
    }
    if (r < config_.clearing_fraction + 0.03) {
      overlay.close_edge(e);
    } else {
      overlay.set_edge(e, {1.0 + 3.0 * unit(rng_), unit(rng_) < 0.5 ? 60.0 * unit(rng_) : 0.0});
    }
    congested_.push_back(e);
    return e;
  }

 private:
  const maps::RoadGraph& graph_;
  const ReplanBenchConfig& config_;
  std::mt19937_64& rng_;
  std::vector<EdgeId> congested_;  // may hold duplicates; clearing an edge twice is harmless
};

double mean_of(const std::vector<double>& xs) {
  return xs.empty() ? 0.0 : std::accumulate(xs.begin(), xs.end(), 0.0) / static_cast<double>(xs.size());
}

}  // namespace

void write_samples_csv(std::ostream& out, const std::vector<ReplanSample>& samples) {
  out << "trip,step,dstar_ms,astar_ms,dijkstra_ms,dstar_expanded,dstar_raised,astar_settled,route_edges_before,reachable,"
         "dstar_path_checks,cch_customization_ms,cch_repair_ms,cch_expanded,cch_changed_arcs,lazy_customization_ms,"
         "lazy_repair_ms,lazy_repairs\n";
  for (const ReplanSample& r : samples) {
    out << r.trip << ',' << r.step << ',' << r.dstar_ms << ',' << r.astar_ms << ',' << r.dijkstra_ms << ','
        << r.dstar_expanded << ',' << r.dstar_raised << ',' << r.astar_settled << ',' << r.route_edges_before << ','
        << (r.reachable ? 1 : 0) << ',' << r.dstar_path_checks << ',' << r.cch_customization_ms << ','
        << r.cch_repair_ms << ',' << r.cch_expanded << ',' << r.cch_changed_arcs << ',' << r.lazy_customization_ms << ','
        << r.lazy_repair_ms << ',' << r.lazy_repairs << '\n';
  }
}

LatencySummary summarize_ms(std::vector<double> samples) {
  LatencySummary s;
  s.count = samples.size();
  if (samples.empty()) return s;
  std::sort(samples.begin(), samples.end());
  auto rank = [&](double q) {
    const auto i = static_cast<std::size_t>(std::ceil(q * static_cast<double>(samples.size()))) - 1;
    return samples[std::min(i, samples.size() - 1)];
  };
  s.p50_ms = rank(0.50);
  s.p95_ms = rank(0.95);
  s.p99_ms = rank(0.99);
  s.max_ms = samples.back();
  double sum = 0;
  for (double x : samples) sum += x;
  s.mean_ms = sum / static_cast<double>(samples.size());
  return s;
}

ReplanBenchResult run_replan_bench(const maps::RoadGraph& graph, const ReplanBenchConfig& config) {
  if (config.trips == 0) throw std::invalid_argument("--trips must be at least 1");
  if (!(config.on_route_fraction >= 0) || !(config.near_route_fraction >= 0) ||
      config.on_route_fraction + config.near_route_fraction > 1.0) {
    throw std::invalid_argument("--on-route and --near-route fractions must be >= 0 and sum to at most 1");
  }
  if (!(config.clearing_fraction >= 0) || config.clearing_fraction > 0.97) {
    throw std::invalid_argument("--clearing fraction must be in [0, 0.97]");
  }
  if (!(config.drive_step_s > 0)) throw std::invalid_argument("drive step must be positive");

  std::mt19937_64 rng(config.seed);
  const double diagonal = maps::distance_m(graph.min_corner(), graph.max_corner());
  const double min_trip = config.min_trip_m > 0 ? config.min_trip_m : std::min(5000.0, diagonal / 3.0);
  const planner::VehicleProfile vehicle{config.vmax_kmh / 3.6};

  ReplanBenchResult res;
  res.nodes = graph.node_count();
  res.landmarks = graph.landmark_count();
  res.edges = graph.edge_count();
  std::vector<double> t_dstar, t_astar, t_dijkstra, t_dstar0, t_astar0;
  std::vector<double> planner_bytes;
  double expanded = 0, rekeyed = 0, raised = 0, path_checks = 0, astar_settled = 0, dijkstra_settled = 0;
  planner::OneToOneSearch astar, dijkstra;
  // Trips start and end on the main component, where every pair of roads is joined (the map keeps
  // cut-off roads too, which no trip between random roads could reach).
  std::vector<EdgeId> main_edges;
  for (EdgeId e : graph.edges()) {
    if (graph.in_main_component(e)) main_edges.push_back(e);
  }
  if (main_edges.empty()) throw std::invalid_argument("bench replan: the map's main component has no roads");
  std::uniform_int_distribution<std::size_t> any_edge(0, main_edges.size() - 1);
  auto t_pre = Clock::now();
  std::optional<planner::CchTopology> topology;
  if (config.eager_hierarchy || config.lazy_hierarchy) {
    topology.emplace(graph.turns());
    res.cch_preprocessing_s = ms_since(t_pre) / 1000.0;
    res.cch_arcs = topology->arc_count();
    res.cch_topology_bytes = topology->memory_bytes();
  }
  std::vector<double> t_cch_full, t_cch, t_cch_custom, t_cch_repair, t_cch0, cch_bytes;
  double cch_changed = 0, cch_expanded = 0, cch_vertices = 0, cch_searched = 0;
  std::vector<double> t_lazy, t_lazy_custom, t_lazy_repair, t_lazy_full;
  double lazy_changed = 0, lazy_repairs = 0, lazy_settled = 0;
  std::vector<double> lazy_bytes;
  std::vector<std::uint32_t> changed_arcs, lazy_arcs;
  maps::ProgressBar progress("bench replan", config.trips);

  for (std::uint32_t trip = 0; trip < config.trips; ++trip) {
    planner::CostOverlay overlay(graph);
    const planner::TravelCost cost(graph, overlay, vehicle);
    UpdateGenerator updates(graph, config, rng);
    EdgePoint start, goal;
    for (int attempt = 0;; ++attempt) {
      start = {main_edges[any_edge(rng)], 0.0};
      goal = {main_edges[any_edge(rng)], 0.0};
      start.offset_m = graph.length_m(start.edge) * 0.5;
      goal.offset_m = graph.length_m(goal.edge) * 0.5;
      if (maps::distance_m(graph.point_along(start.edge, start.offset_m), graph.point_along(goal.edge, goal.offset_m)) >=
              min_trip ||
          attempt > 1000) {
        break;
      }
    }
    auto t0 = Clock::now();
    planner::DStarLite dstar(cost, {start}, {goal}, planner::DStarLiteOptions{config.lazy_raises});
    dstar.replan();
    planner::Route route = dstar.route();
    t_dstar0.push_back(ms_since(t0));
    t0 = Clock::now();
    (void)astar.run(planner::SearchSpace(cost, {start}, {goal}), true);
    t_astar0.push_back(ms_since(t0));
    ++res.trips;
    std::optional<planner::CchMetric> metric, lazy_metric;
    std::optional<planner::CchDStarLite> cch_dstar, lazy_dstar;
    if (config.eager_hierarchy) {
      t0 = Clock::now();
      metric.emplace(*topology, cost);
      t_cch_full.push_back(ms_since(t0));
      res.cch_metric_bytes = metric->memory_bytes();
      t0 = Clock::now();
      cch_dstar.emplace(*metric, std::vector<EdgePoint>{start}, std::vector<EdgePoint>{goal},
                        planner::DStarLiteOptions{config.lazy_raises});
      cch_dstar->replan();
      (void)cch_dstar->route();
      t_cch0.push_back(ms_since(t0));
    }
    if (config.lazy_hierarchy) {
      t0 = Clock::now();
      lazy_metric.emplace(*topology, cost, planner::CchMetricOptions{.lazy_rises = true});
      t_lazy_full.push_back(ms_since(t0));
      res.lazy_metric_bytes = lazy_metric->memory_bytes();
      lazy_dstar.emplace(*lazy_metric, std::vector<EdgePoint>{start}, std::vector<EdgePoint>{goal},
                         planner::DStarLiteOptions{config.lazy_raises});
      (void)planner::replan_settled(*lazy_metric, *lazy_dstar);
    }

    std::unordered_set<std::uint32_t> changed_set;
    for (std::uint32_t step = 0; step < config.max_replans_per_trip && route.found; ++step) {
      const auto position = drive(cost, route, config.drive_step_s);
      if (!position) break;

      changed_set.clear();
      std::vector<EdgeId> changed;
      for (EdgeId e : updates.pick(route)) {
        const EdgeId touched = updates.apply(e, overlay);
        if (changed_set.insert(touched.v).second) changed.push_back(touched);
      }

      // The lazy hierarchy goes first, straight after the batch: the searches that follow read
      // the same graph, overlay and hierarchy, and would warm its caches: timed after the eager one
      // it measures about 15 % faster at p50 (see docs/routing.md, Lazy rises).
      double lazy_custom_ms = 0, lazy_repair_ms = 0;
      planner::SettledReplan lazy;
      if (lazy_dstar) {
        t0 = Clock::now();
        lazy_arcs.clear();
        (void)lazy_metric->edges_changed(changed, lazy_arcs);
        lazy_custom_ms = ms_since(t0);
        t0 = Clock::now();
        lazy_dstar->move_start({*position});
        lazy_dstar->edges_changed(changed);
        lazy_dstar->arcs_changed(lazy_arcs);
        lazy = planner::replan_settled(*lazy_metric, *lazy_dstar);
        lazy_repair_ms = ms_since(t0);
        t_lazy_custom.push_back(lazy_custom_ms);
        t_lazy_repair.push_back(lazy_repair_ms);
        t_lazy.push_back(lazy_custom_ms + lazy_repair_ms);
        lazy_changed += static_cast<double>(lazy_arcs.size());
        lazy_repairs += lazy.repairs;
        lazy_settled += static_cast<double>(lazy.settled);
        res.lazy_max_repairs = std::max<std::uint64_t>(res.lazy_max_repairs, lazy.repairs);
      }

      t0 = Clock::now();
      dstar.move_start({*position});
      dstar.edges_changed(changed);
      const auto stats = dstar.replan();
      planner::Route next = dstar.route();
      t_dstar.push_back(ms_since(t0));
      expanded += static_cast<double>(stats.expanded);
      rekeyed += static_cast<double>(stats.rekeyed);
      raised += static_cast<double>(stats.underconsistent);
      path_checks += static_cast<double>(stats.path_checks);

      double custom_ms = 0, repair_ms = 0;
      planner::ReplanStats cch_stats;
      planner::Route cch_route;
      changed_arcs.clear();
      if (cch_dstar) {
        t0 = Clock::now();
        (void)metric->edges_changed(changed, changed_arcs);
        custom_ms = ms_since(t0);
        t0 = Clock::now();
        cch_dstar->move_start({*position});
        cch_dstar->edges_changed(changed);
        cch_dstar->arcs_changed(changed_arcs);
        cch_stats = cch_dstar->replan();
        cch_route = cch_dstar->route();
        repair_ms = ms_since(t0);
        t_cch_custom.push_back(custom_ms);
        t_cch_repair.push_back(repair_ms);
        t_cch.push_back(custom_ms + repair_ms);
        cch_changed += static_cast<double>(changed_arcs.size());
        cch_expanded += static_cast<double>(cch_stats.expanded);
        cch_vertices += static_cast<double>(cch_dstar->space().upward_size() + cch_dstar->space().downward_size());
        cch_searched += static_cast<double>(cch_dstar->space().downward_size() + 2);
      }

      const planner::SearchSpace space(cost, {*position}, {goal});
      planner::SearchStats s_astar, s_dijkstra;
      t0 = Clock::now();
      const planner::Route a = astar.run(space, true, &s_astar);
      t_astar.push_back(ms_since(t0));
      astar_settled += static_cast<double>(s_astar.settled);

      if (config.run_dijkstra) {
        t0 = Clock::now();
        const planner::Route d = dijkstra.run(space, false, &s_dijkstra);
        t_dijkstra.push_back(ms_since(t0));
        dijkstra_settled += static_cast<double>(s_dijkstra.settled);
        if (costs_differ(dstar.cost_to_goal_s(), d.travel_time_s) || costs_differ(next.travel_time_s, d.travel_time_s)) {
          ++res.mismatches;
          spdlog::warn("event=mismatch trip={} step={} dstar_s={:.9f} dijkstra_s={:.9f}", trip, step,
                       dstar.cost_to_goal_s(), d.travel_time_s);
        }
        if (costs_differ(a.travel_time_s, d.travel_time_s)) ++res.astar_mismatches;
        if (cch_dstar && (costs_differ(cch_dstar->cost_to_goal_s(), d.travel_time_s) ||
                          costs_differ(cch_route.travel_time_s, d.travel_time_s))) {
          ++res.cch_mismatches;
          spdlog::warn("event=cch_mismatch trip={} step={} cch_s={:.9f} route_s={:.9f} dijkstra_s={:.9f}", trip, step,
                       cch_dstar->cost_to_goal_s(), cch_route.travel_time_s, d.travel_time_s);
        }
        if (lazy_dstar && (costs_differ(lazy_dstar->cost_to_goal_s(), d.travel_time_s) ||
                           costs_differ(lazy.route.travel_time_s, d.travel_time_s))) {
          ++res.lazy_mismatches;
          spdlog::warn("event=lazy_cch_mismatch trip={} step={} bound_s={:.9f} route_s={:.9f} dijkstra_s={:.9f}", trip,
                       step, lazy_dstar->cost_to_goal_s(), lazy.route.travel_time_s, d.travel_time_s);
        }
      }
      ++res.replans;
      res.samples.push_back({trip, step, t_dstar.back(), t_astar.back(), config.run_dijkstra ? t_dijkstra.back() : 0.0,
                             stats.expanded, stats.underconsistent, s_astar.settled, stats.path_checks,
                             route.edges.size(), next.found, custom_ms, repair_ms, cch_stats.expanded,
                             changed_arcs.size(), lazy_custom_ms, lazy_repair_ms, lazy.repairs});
      // Unchanged means: the new route is the rest of the old one from the vehicle's edge on.
      const auto from = std::find(route.edges.begin(), route.edges.end(), next.edges.empty() ? kInvalidEdge : next.edges.front());
      if (!std::equal(from, route.edges.end(), next.edges.begin(), next.edges.end())) ++res.route_changes;
      route = std::move(next);
    }
    planner_bytes.push_back(static_cast<double>(dstar.memory_bytes()));
    if (cch_dstar) cch_bytes.push_back(static_cast<double>(cch_dstar->memory_bytes()));
    if (lazy_dstar) lazy_bytes.push_back(static_cast<double>(lazy_dstar->memory_bytes()));
    progress.update(trip + 1);
  }
  progress.finish();

  res.dstar = summarize_ms(t_dstar);
  res.astar = summarize_ms(t_astar);
  res.dijkstra = summarize_ms(t_dijkstra);
  res.dstar_initial = summarize_ms(t_dstar0);
  res.astar_initial = summarize_ms(t_astar0);
  const double n = res.replans > 0 ? static_cast<double>(res.replans) : 1.0;
  res.dstar_mean_expanded = expanded / n;
  // A trip's planner at its end: what a mission that drove that trip holds.
  res.dstar_bytes_per_planner = mean_of(planner_bytes);
  res.dstar_max_bytes_per_planner = planner_bytes.empty() ? 0.0 : *std::max_element(planner_bytes.begin(), planner_bytes.end());
  res.dstar_mean_rekeyed = rekeyed / n;
  res.dstar_mean_raised = raised / n;
  res.dstar_mean_path_checks = path_checks / n;
  res.astar_mean_settled = astar_settled / n;
  res.dijkstra_mean_settled = dijkstra_settled / n;
  res.cch_customization_full = summarize_ms(t_cch_full);
  res.cch_dstar = summarize_ms(t_cch);
  res.cch_customization = summarize_ms(t_cch_custom);
  res.cch_repair = summarize_ms(t_cch_repair);
  res.cch_dstar_initial = summarize_ms(t_cch0);
  res.cch_mean_changed_arcs = cch_changed / n;
  res.cch_mean_expanded = cch_expanded / n;
  res.cch_mean_vertices = cch_vertices / n;
  res.cch_mean_searched_vertices = cch_searched / n;
  res.cch_bytes_per_planner = mean_of(cch_bytes);
  res.cch_max_bytes_per_planner = cch_bytes.empty() ? 0.0 : *std::max_element(cch_bytes.begin(), cch_bytes.end());
  res.lazy_dstar = summarize_ms(t_lazy);
  res.lazy_customization = summarize_ms(t_lazy_custom);
  res.lazy_repair = summarize_ms(t_lazy_repair);
  res.lazy_customization_full = summarize_ms(t_lazy_full);
  res.lazy_mean_changed_arcs = lazy_changed / n;
  res.lazy_mean_repairs = lazy_repairs / n;
  res.lazy_mean_settled = lazy_settled / n;
  res.lazy_bytes_per_planner = mean_of(lazy_bytes);
  return res;
}

nlohmann::json to_json(const LatencySummary& s) {
  return {{"count", s.count},   {"p50_ms", s.p50_ms}, {"p95_ms", s.p95_ms}, {"p99_ms", s.p99_ms},
          {"max_ms", s.max_ms}, {"mean_ms", s.mean_ms}};
}

namespace {

// D* Lite on the hierarchy with lazy rises, beside the eager one when that ran too.
nlohmann::json lazy_json(nlohmann::json j, const ReplanBenchResult& r) {
  if (r.lazy_dstar.count == 0) return j;
  nlohmann::json& l = j["dstar_cch_lazy"];
  l = to_json(r.lazy_dstar);
  l["customization"] = to_json(r.lazy_customization);
  l["repair"] = to_json(r.lazy_repair);
  l["mean_changed_arcs"] = r.lazy_mean_changed_arcs;
  l["mean_repairs"] = r.lazy_mean_repairs;
  l["max_repairs"] = r.lazy_max_repairs;
  l["mean_settled_arcs"] = r.lazy_mean_settled;
  l["mean_bytes_per_planner"] = r.lazy_bytes_per_planner;
  l["full_customization"] = to_json(r.lazy_customization_full);
  l["metric_bytes"] = r.lazy_metric_bytes;
  l["topology_bytes"] = r.cch_topology_bytes;
  l["mismatches"] = r.lazy_mismatches;
  if (r.cch_dstar.count > 0) {
    l["speedup_p50_vs_dstar_cch"] = r.lazy_dstar.p50_ms > 0 ? r.cch_dstar.p50_ms / r.lazy_dstar.p50_ms : 0.0;
    l["speedup_p99_vs_dstar_cch"] = r.lazy_dstar.p99_ms > 0 ? r.cch_dstar.p99_ms / r.lazy_dstar.p99_ms : 0.0;
  }
  return j;
}

}  // namespace

nlohmann::json to_json(const ReplanBenchResult& r, const ReplanBenchConfig& c) {
  auto ratio = [](double a, double b) { return b > 0 ? a / b : 0.0; };
  nlohmann::json j;
  j["graph"] = {{"nodes", r.nodes}, {"edges", r.edges}};
  j["trips"] = r.trips;
  j["updates_per_batch"] = c.updates_per_batch;
  j["seed"] = c.seed;
  j["drive_step_s"] = c.drive_step_s;
  j["update_mix"] = {{"on_route", c.on_route_fraction},
                     {"near_route", c.near_route_fraction},
                     {"elsewhere", 1.0 - c.on_route_fraction - c.near_route_fraction},
                     {"clearing", c.clearing_fraction}};
  j["replans"] = r.replans;
  j["route_changes"] = r.route_changes;
  j["dstar"] = to_json(r.dstar);
  j["dstar"]["mean_expanded"] = r.dstar_mean_expanded;
  j["dstar"]["mean_bytes_per_planner"] = r.dstar_bytes_per_planner;
  j["dstar"]["max_bytes_per_planner"] = r.dstar_max_bytes_per_planner;
  // Replans that end with the goal cut off must visit everything the start (Dijkstra, A*) or the
  // old search tree (D* Lite) reaches to prove it; shown apart so they do not hide the rest.
  std::vector<double> dstar_ok, astar_ok;
  std::size_t cut_off = 0;
  for (const ReplanSample& x : r.samples) {
    if (!x.reachable) {
      ++cut_off;
      continue;
    }
    dstar_ok.push_back(x.dstar_ms);
    astar_ok.push_back(x.astar_ms);
  }
  j["dstar"]["goal_reachable"] = to_json(summarize_ms(dstar_ok));
  j["replans_goal_cut_off"] = cut_off;
  j["heuristic"] = "ALT, " + std::to_string(r.landmarks) + " landmarks (free-flow time)";
  j["dstar"]["mean_rekeyed"] = r.dstar_mean_rekeyed;
  j["dstar"]["mean_raised"] = r.dstar_mean_raised;
  j["dstar"]["lazy_raises"] = c.lazy_raises;
  j["dstar"]["mean_path_checks"] = r.dstar_mean_path_checks;
  j["astar"] = to_json(r.astar);
  j["astar"]["goal_reachable"] = to_json(summarize_ms(astar_ok));
  j["astar"]["mean_settled"] = r.astar_mean_settled;
  if (c.run_dijkstra) {
    j["dijkstra"] = to_json(r.dijkstra);
    j["dijkstra"]["mean_settled"] = r.dijkstra_mean_settled;
  }
  j["initial_plan"] = {{"dstar", to_json(r.dstar_initial)}, {"astar", to_json(r.astar_initial)}};
  j["speedup_p50_vs_astar"] = ratio(r.astar.p50_ms, r.dstar.p50_ms);
  j["speedup_p50_vs_dijkstra"] = c.run_dijkstra ? ratio(r.dijkstra.p50_ms, r.dstar.p50_ms) : 0.0;
  j["mismatches"] = r.mismatches;
  j["astar_mismatches"] = r.astar_mismatches;
  j["hierarchy"] = c.eager_hierarchy ? (c.lazy_hierarchy ? "both" : "eager") : (c.lazy_hierarchy ? "lazy" : "none");
  if (c.eager_hierarchy || c.lazy_hierarchy) {
    j["hierarchy_preprocessing_s"] = r.cch_preprocessing_s;
    j["hierarchy_arcs"] = r.cch_arcs;
  }
  if (!c.eager_hierarchy) return lazy_json(j, r);
  j["dstar_cch"] = to_json(r.cch_dstar);
  j["dstar_cch"]["customization"] = to_json(r.cch_customization);
  j["dstar_cch"]["repair"] = to_json(r.cch_repair);
  j["dstar_cch"]["initial_plan"] = to_json(r.cch_dstar_initial);
  j["dstar_cch"]["full_customization"] = to_json(r.cch_customization_full);
  j["dstar_cch"]["preprocessing_s"] = r.cch_preprocessing_s;
  j["dstar_cch"]["arcs"] = r.cch_arcs;
  // Shared by every mission on the map (the metric: by every mission with the same cost model).
  j["dstar_cch"]["topology_bytes"] = r.cch_topology_bytes;
  j["dstar_cch"]["metric_bytes"] = r.cch_metric_bytes;
  j["dstar_cch"]["mean_changed_arcs"] = r.cch_mean_changed_arcs;
  j["dstar_cch"]["mean_expanded"] = r.cch_mean_expanded;
  j["dstar_cch"]["mean_vertices"] = r.cch_mean_vertices;
  j["dstar_cch"]["mean_searched_vertices"] = r.cch_mean_searched_vertices;
  j["dstar_cch"]["mean_bytes_per_planner"] = r.cch_bytes_per_planner;
  j["dstar_cch"]["max_bytes_per_planner"] = r.cch_max_bytes_per_planner;
  j["dstar_cch"]["mismatches"] = r.cch_mismatches;
  return lazy_json(j, r);
}

}  // namespace corridor::bench
