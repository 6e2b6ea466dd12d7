#include "sim/experiment_tables.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <tuple>

#include "planner/experiments/statistics.hpp"
#include "planner/experiments/svg_chart.hpp"
#include "sim/errors.hpp"

namespace corridor::sim {
namespace {

using planner::quantile;
using Demand = std::pair<double, double>;  // volume, scale

void write_text(const std::filesystem::path& file, const std::string& text) {
  std::ofstream out(file, std::ios::trunc | std::ios::binary);
  out << text;
  if (!out) throw SimError("cannot write " + file.string());
}

std::string demand_label(const RunRecord& r) {
  return r.volume > 0.0 ? fmt::format("v{:g}", r.volume) : fmt::format("x{:g}", r.demand_scale);
}

std::string label(EvRouting r, EvSignals s) { return fmt::format("{} / {}", to_string(r), to_string(s)); }

std::string run_name(const RunRecord& r) {
  return r.with_ev ? fmt::format("{} at {} seed {}", label(r.routing, r.signals), demand_label(r), r.seed)
                   : fmt::format("the run without the EV at {} seed {}", demand_label(r), r.seed);
}

// RFC 4180: a field with a comma, quote or line break is quoted, its quotes doubled.
std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\r\n") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

std::string number_or_empty(double v, const char* format) {
  return std::isfinite(v) ? fmt::format(fmt::runtime(format), v) : std::string{};
}

struct Cell {
  std::size_t planned = 0, failed = 0;
  std::map<std::uint64_t, const ExperimentRow*> by_seed;  // completed runs
  int arrived = 0, collisions = 0, teleports = 0;
  std::size_t violations = 0;
  [[nodiscard]] std::vector<double> times(const std::set<std::uint64_t>* seeds = nullptr) const {
    std::vector<double> v;
    for (const auto& [seed, row] : by_seed) {
      if (seeds == nullptr || seeds->contains(seed)) v.push_back(row->ev_time_s());
    }
    return v;
  }
  [[nodiscard]] std::vector<double> delays() const {
    std::vector<double> v;
    for (const auto& [seed, row] : by_seed) {
      if (const double d = row->others_delay_rel(); std::isfinite(d)) v.push_back(d);
    }
    return v;
  }
};

double median_or_nan(const std::vector<double>& v) { return v.empty() ? std::nan("") : quantile(v, 0.5); }

}  // namespace

double ExperimentRow::others_delay_rel() const {
  if (!ok() || !baseline_time_loss_s) return std::nan("");
  return *baseline_time_loss_s > 0.0 ? run.result.others_mean_time_loss_s / *baseline_time_loss_s - 1.0 : 0.0;
}

double ExperimentRow::ev_time_s() const {
  if (!ok()) return std::nan("");
  return run.result.ev_arrived ? run.result.ev_travel_time_s : std::max(0.0, run.result.end_time_s - run.ev_depart_s);
}

ExperimentTables write_experiment_tables(std::vector<PlannedRecord> runs, const std::filesystem::path& out_dir) {
  std::sort(runs.begin(), runs.end(), [](const PlannedRecord& a, const PlannedRecord& b) { return a.file < b.file; });
  runs.erase(std::unique(runs.begin(), runs.end(), [](const PlannedRecord& a, const PlannedRecord& b) { return a.file == b.file; }),
             runs.end());

  ExperimentTables out;
  std::vector<RunRecord> records;
  for (const PlannedRecord& planned : runs) {
    std::ifstream in(planned.file);
    try {
      if (!in) {
        throw SimError(planned.file.string() + ": no result (the run ended without one; see its .console.log and .sumo.log)");
      }
      nlohmann::json j;
      try {
        in >> j;
      } catch (const nlohmann::json::exception&) {
        throw SimError(planned.file.string() + ": no result (the run did not finish)");
      }
      records.push_back(record_from_json(j, planned.file.string()));
    } catch (const SimError& e) {
      // Where the plan knows the run, it is a failed row; else it can only be listed.
      if (planned.identity) {
        records.push_back(failed_run(*planned.identity, e.what()));
      } else {
        out.failures.push_back(e.what());
      }
    }
  }
  if (records.empty()) {
    throw SimError("no run records (*.run.json) to collect" + (out.failures.empty() ? std::string{} : ": " + out.failures.front()));
  }
  const std::string scenario = records.front().scenario;
  for (const RunRecord& r : records) {
    if (r.scenario != scenario) throw SimError("the records mix scenarios '" + scenario + "' and '" + r.scenario + "'");
    if (r.with_ev && (r.vicinity != records.front().vicinity || r.evs != records.front().evs)) {
      throw SimError("the records mix vicinity-aware and route-only preemption, or numbers of EVs: collect them apart");
    }
  }
  const bool vicinity = std::all_of(records.begin(), records.end(), [](const RunRecord& r) { return r.vicinity; });
  std::uint32_t evs = 1;
  for (const RunRecord& r : records) evs = std::max(evs, r.evs);

  using Key = std::tuple<double, double, std::uint64_t>;  // volume, scale, seed
  std::map<Key, const RunRecord*> baselines;
  for (const RunRecord& r : records) {
    if (r.with_ev) continue;
    baselines[{r.volume, r.demand_scale, r.seed}] = &r;
    if (r.status == RunStatus::failed) out.failures.push_back(run_name(r) + ": " + r.failure);
  }
  for (const RunRecord& r : records) {
    if (!r.with_ev) continue;
    ExperimentRow row{r, std::nullopt};
    const auto it = baselines.find({r.volume, r.demand_scale, r.seed});
    if (it != baselines.end() && it->second->status == RunStatus::ok) row.baseline_time_loss_s = it->second->result.others_mean_time_loss_s;
    if (r.status == RunStatus::failed) out.failures.push_back(run_name(r) + ": " + r.failure);
    if (r.status == RunStatus::ok && it == baselines.end()) {
      out.failures.push_back(run_name(r) + ": no run without the EV for its demand and seed, so no others' delay");
    }
    out.rows.push_back(std::move(row));
  }
  auto& rows = out.rows;
  std::sort(rows.begin(), rows.end(), [](const ExperimentRow& a, const ExperimentRow& b) {
    return std::tuple(a.run.volume, a.run.demand_scale, a.run.seed, a.run.routing, a.run.signals) <
           std::tuple(b.run.volume, b.run.demand_scale, b.run.seed, b.run.routing, b.run.signals);
  });
  for (const auto& f : out.failures) spdlog::warn("event=sumo_run_failed detail=\"{}\"", f);

  std::string csv =
      "routing,signals,volume,seed,ev_travel_time_s,ev_stops,ev_wait_s,preempted_signals,others_delay_rel,collisions,"
      "teleports,ev_arrived,ev_time_loss_s,route_changes,replans,lights_taken_over,lights_back_on_program,"
      "safety_violations,others,others_mean_time_loss_s,baseline_time_loss_s,demand_scale,scenario,ev_from,ev_to,"
      "vicinity,evs,evs_arrived,evs_travel_time_mean_s,deferrals,status,failure,collisions_at_held_lights\n";
  for (const ExperimentRow& row : rows) {
    const RunRecord& r = row.run;
    const std::string identity_head = fmt::format("{},{},{:g},{}", to_string(r.routing), to_string(r.signals), r.volume, r.seed);
    const std::string identity_tail = fmt::format("{:g},{},{},{},{},{}", r.demand_scale, csv_field(r.scenario), csv_field(r.ev_from),
                                                  csv_field(r.ev_to), r.vicinity ? 1 : 0, r.evs);
    if (!row.ok()) {
      // A run that did not complete has no figures: empty fields, not zeros that read as results.
      csv += identity_head + std::string(17, ',') + number_or_empty(row.baseline_time_loss_s.value_or(std::nan("")), "{:.3f}") + "," +
             identity_tail + ",,,,failed," + csv_field(r.failure) + ",\n";
      continue;
    }
    std::size_t evs_arrived = 0;
    double evs_time = 0.0;
    for (const EvOutcome& e : r.result.evs) {
      evs_arrived += e.arrived ? 1 : 0;
      evs_time += e.arrived ? e.travel_time_s : 0.0;
    }
    const auto at_held = std::count_if(r.result.collision_records.begin(), r.result.collision_records.end(),
                                       [](const CollisionRecord& c) { return c.held_by_corridor; });
    csv += fmt::format("{},{:.1f},{},{:.1f},{},{},{},{},{},{:.1f},{},{},{},{},{},{},{:.3f},{},{},{},{:.1f},{},ok,,{}\n",
                       identity_head, r.result.ev_travel_time_s, r.result.ev_stops, r.result.ev_wait_s, r.result.preempted_signals,
                       number_or_empty(row.others_delay_rel(), "{:.4f}"), r.result.collisions, r.result.teleports,
                       r.result.ev_arrived ? 1 : 0, r.result.ev_time_loss_s, r.result.route_changes, r.result.replans,
                       r.result.lights_taken_over, r.result.lights_back_on_program, r.result.safety_violations.size(),
                       r.result.others, r.result.others_mean_time_loss_s,
                       number_or_empty(row.baseline_time_loss_s.value_or(std::nan("")), "{:.3f}"), identity_tail, evs_arrived,
                       evs_arrived > 0 ? evs_time / static_cast<double>(evs_arrived) : 0.0, r.result.deferrals, at_held);
  }
  std::filesystem::create_directories(out_dir);
  write_text(out_dir / "sumo_runs.csv", csv);

  // The demand levels, routings and strategies present, in order.
  std::set<Demand> demand_set;
  std::set<EvRouting> routing_set;
  std::set<EvSignals> signal_set;
  std::set<std::uint64_t> seeds;
  for (const ExperimentRow& row : rows) {
    demand_set.insert({row.run.volume, row.run.demand_scale});
    routing_set.insert(row.run.routing);
    signal_set.insert(row.run.signals);
    seeds.insert(row.run.seed);
  }
  const std::vector<Demand> demands(demand_set.begin(), demand_set.end());
  const bool scaled = !demands.empty() && demands.front().first == 0.0;
  const auto demand_name = [&](const Demand& d) {
    return scaled ? fmt::format("demand x{:g}", d.second) : fmt::format("{:g} veh/h", d.first);
  };

  std::map<std::tuple<EvRouting, EvSignals, Demand>, Cell> cells;
  for (const ExperimentRow& row : rows) {
    Cell& c = cells[{row.run.routing, row.run.signals, {row.run.volume, row.run.demand_scale}}];
    ++c.planned;
    if (!row.ok()) {
      ++c.failed;
      continue;
    }
    c.by_seed[row.run.seed] = &row;
    c.arrived += row.run.result.ev_arrived ? 1 : 0;
    c.collisions += row.run.result.collisions;
    c.teleports += row.run.result.teleports;
    c.violations += row.run.result.safety_violations.size();
  }

  std::string summary =
      "routing,signals,volume,runs,arrived,ev_travel_time_median_s,ev_travel_time_q1_s,ev_travel_time_q3_s,"
      "ev_stops_median,others_delay_rel_median,others_delay_rel_q1,others_delay_rel_q3,collisions,teleports,"
      "safety_violations,demand_scale,planned,failed\n";
  std::string md = fmt::format(
      "Scenario `{}`, {} seeds per demand level, {} preemption{}. EV travel time: median [IQR] in s over the runs that "
      "completed (an EV that did not arrive counts with the time it was still driving), and n, the runs that completed. "
      "Others: median change of the other vehicles' mean time loss against the same run without the EV.\n\n"
      "| routing / signals |",
      scenario, seeds.size(), vicinity ? "vicinity-aware" : "route-only",
      evs > 1 ? fmt::format(", {} EVs per run (the first EV's figures; every EV's in sumo_runs.csv)", evs) : std::string{});
  for (const auto& d : demands) md += " " + demand_name(d) + " |";
  md += "\n|---|";
  for (std::size_t i = 0; i < demands.size(); ++i) md += "---|";
  md += "\n";
  std::vector<planner::ChartSeries> travel, delay;
  for (EvRouting r : routing_set) {
    for (EvSignals s : signal_set) {
      planner::ChartSeries ts{label(r, s), {}, {}}, ds{label(r, s), {}, {}};
      std::string line = "| " + label(r, s) + " |";
      for (const auto& d : demands) {
        const auto it = cells.find({r, s, d});
        if (it == cells.end()) {
          line += " – |";
          continue;
        }
        const Cell& c = it->second;
        const std::vector<double> tt = c.times();
        const std::vector<double> rel = c.delays();
        std::vector<double> stops;
        for (const auto& [seed, row] : c.by_seed) stops.push_back(row->run.result.ev_stops);
        const auto q = [](const std::vector<double>& v, double p) { return v.empty() ? std::nan("") : quantile(v, p); };
        summary += fmt::format("{},{},{:g},{},{},{},{},{},{},{},{},{},{},{},{},{:g},{},{}\n", to_string(r), to_string(s), d.first,
                               c.by_seed.size(), c.arrived, number_or_empty(q(tt, 0.5), "{:.1f}"),
                               number_or_empty(q(tt, 0.25), "{:.1f}"), number_or_empty(q(tt, 0.75), "{:.1f}"),
                               number_or_empty(q(stops, 0.5), "{:.1f}"), number_or_empty(q(rel, 0.5), "{:.4f}"),
                               number_or_empty(q(rel, 0.25), "{:.4f}"), number_or_empty(q(rel, 0.75), "{:.4f}"), c.collisions,
                               c.teleports, c.violations, d.second, c.planned, c.failed);
        if (tt.empty()) {
          line += fmt::format(" **all {} failed** |", c.planned);
          continue;
        }
        line += fmt::format(" {:.0f} [{:.0f}–{:.0f}], others {}, n={}{}{} |", q(tt, 0.5), q(tt, 0.25), q(tt, 0.75),
                            rel.empty() ? std::string("–") : fmt::format("{:+.1f}%", 100.0 * q(rel, 0.5)), tt.size(),
                            c.arrived == static_cast<int>(tt.size()) ? "" : fmt::format(", {} of {} arrived", c.arrived, tt.size()),
                            c.failed == 0 ? "" : fmt::format(", **{} of {} failed**", c.failed, c.planned));
        ts.x.push_back(scaled ? d.second : d.first);
        ts.y.push_back(q(tt, 0.5));
        if (!rel.empty()) {
          ds.x.push_back(scaled ? d.second : d.first);
          ds.y.push_back(100.0 * q(rel, 0.5));
        }
      }
      md += line + "\n";
      travel.push_back(std::move(ts));
      delay.push_back(std::move(ds));
    }
  }

  // The headline: the best Corridor strategy against a static route with no help (static / none)
  // and against the best of SUMO's bluelight device alone, each median over the same seeds: those
  // where all three completed. Medians over different seeds compare different trips.
  md += "\nBest Corridor strategy per demand level (lowest median EV travel time among the corridor strategies), "
        "against a static route with no help (static / none) and against the best strategy with SUMO's bluelight "
        "device alone, each over the seeds where all three runs completed:\n\n";
  for (const auto& d : demands) {
    const auto cell = [&](EvRouting r, EvSignals s) -> const Cell* {
      const auto it = cells.find({r, s, d});
      return it == cells.end() ? nullptr : &it->second;
    };
    const auto median = [&](EvRouting r, EvSignals s, const std::set<std::uint64_t>* on = nullptr) {
      const Cell* c = cell(r, s);
      return c == nullptr ? std::nan("") : median_or_nan(c->times(on));
    };
    std::optional<std::pair<EvRouting, EvSignals>> best, blue;
    for (EvRouting r : routing_set) {
      for (EvSignals s : signal_set) {
        const double m = median(r, s);
        if (std::isnan(m) || !(preempts(s) || s == EvSignals::bluelight)) continue;
        auto& slot = preempts(s) ? best : blue;
        if (!slot || m < median(slot->first, slot->second)) slot = std::pair(r, s);
      }
    }
    if (!best) {
      md += fmt::format("- {}: no Corridor strategy completed a run\n", demand_name(d));
      continue;
    }
    const Cell& bc = *cell(best->first, best->second);
    const Cell* none = cell(EvRouting::static_route, EvSignals::none);
    const Cell* bluec = blue ? cell(blue->first, blue->second) : nullptr;
    std::set<std::uint64_t> common;
    for (const auto& [seed, row] : bc.by_seed) {
      if ((none == nullptr || none->by_seed.contains(seed)) && (bluec == nullptr || bluec->by_seed.contains(seed))) common.insert(seed);
    }
    const double b = median(best->first, best->second, &common);
    const auto against = [&](const Cell* base, const std::string& name) {
      if (base == nullptr) return fmt::format("no {} run in this matrix", name);
      const double m = median_or_nan(base->times(&common));
      if (std::isnan(m)) return fmt::format("no seed where {} completed too", name);
      return fmt::format("{:+.1f}% against {} ({:.0f} s)", 100.0 * (b / m - 1.0), name, m);
    };
    std::size_t arrived = 0;
    for (std::uint64_t seed : common) arrived += bc.by_seed.at(seed)->run.result.ev_arrived ? 1 : 0;
    const std::vector<double> rel = bc.delays();
    const auto q = [&](double p) { return rel.empty() ? std::nan("") : 100.0 * quantile(rel, p); };
    const std::size_t seeds_planned = bc.planned;
    md += fmt::format("- {}: {} {:.0f} s; {}, {}; over {} of {} seeds{}; others' delay {:+.1f}% [IQR {:+.1f}, {:+.1f}]; "
                      "{} of {} EVs arrived; {} collisions, {} safety violations\n",
                      demand_name(d), label(best->first, best->second), b, against(none, "static / none"),
                      against(bluec, blue ? label(blue->first, blue->second) : std::string("bluelight")), common.size(),
                      seeds_planned, common.size() < seeds_planned ? " (**the others did not complete**)" : "", q(0.5), q(0.25),
                      q(0.75), arrived, common.size(), bc.collisions, bc.violations);
  }
  if (!out.failures.empty()) {
    md += fmt::format("\n**{} run(s) did not complete**, each a row of sumo_runs.csv with status failed where the matrix "
                      "knows it:\n\n",
                      out.failures.size());
    for (const auto& f : out.failures) md += "- " + f + "\n";
  }
  // Every collision traced to its light, so that one can be told apart from Corridor's doing.
  std::string collisions;
  for (const ExperimentRow& row : rows) {
    for (const CollisionRecord& c : row.run.result.collision_records) {
      const std::string links =
          c.collider_link < 0 || c.victim_link < 0 ? std::string("")
          : c.collider_link == c.victim_link      ? fmt::format(", both on link {}", c.collider_link)
                                                  : fmt::format(", links {} and {} ({})", c.collider_link, c.victim_link,
                                                                c.links_conflict ? "foes" : "not foes");
      collisions += fmt::format("- {}, t={:.0f} s: {} ({}, {}) into {} ({}, {}), {} on {}{}; lights: {} {}, {} {}{}{}\n",
                                run_name(row.run), c.time_s, c.collider, c.collider_type, c.collider_lane, c.victim,
                                c.victim_type, c.victim_lane, c.kind, c.lane, c.tls.empty() ? "" : " under light " + c.tls,
                                c.collider, c.collider_light, c.victim, c.victim_light, links,
                                c.held_by_corridor ? "; the light was held by Corridor" : "");
    }
  }
  if (!collisions.empty()) md += "\nCollisions, each traced to the light over it:\n\n" + collisions;
  write_text(out_dir / "sumo_summary.csv", summary);
  write_text(out_dir / "sumo_summary.md", md);
  const bool injected = std::any_of(rows.begin(), rows.end(), [](const ExperimentRow& r) { return r.run.inject_on_route; });
  const std::string x_label = scaled     ? "demand scale (x the scenario's own demand)"
                              : injected ? "volume injected on the EV's static route (vehicles/hour)"
                                         : "background volume (vehicles/hour)";
  // A plot needs a point: a matrix where every run failed has none, and its plots are left out.
  const auto plot = [&](const std::string& file, const planner::ChartText& spec, std::vector<planner::ChartSeries> series,
                        bool from_zero) {
    std::erase_if(series, [](const planner::ChartSeries& s) { return s.y.empty(); });
    std::error_code ec;
    std::filesystem::remove(out_dir / file, ec);
    if (!series.empty()) write_text(out_dir / file, planner::render_line_chart(spec, series, from_zero));
  };
  plot("sumo_travel_time.svg",
       {fmt::format("{}: EV travel time against demand", scenario), x_label, "median EV travel time (s)"}, std::move(travel), true);
  plot("sumo_others_delay.svg",
       {fmt::format("{}: other vehicles' delay against demand", scenario), x_label, "median change of mean time loss (%)"},
       std::move(delay), false);
  return out;
}

}  // namespace corridor::sim
