#include "sim/scenario_builder.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <cstdlib>
#include <fstream>
#include <optional>

#include "maps/sumo_net.hpp"
#include "sim/errors.hpp"
#include "sim/process.hpp"

namespace corridor::sim {
namespace {

std::filesystem::path sumo_home() {
  const char* home = std::getenv("SUMO_HOME");
  return home != nullptr && *home != '\0' ? std::filesystem::path(home) : std::filesystem::path("/usr/share/sumo");
}

void prepare(const std::filesystem::path& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw SimError("cannot create the scenario directory '" + dir.string() + "': " + ec.message());
}

bool up_to_date(const std::filesystem::path& out, const std::filesystem::path& input) {
  std::error_code ec;
  return std::filesystem::exists(out) && std::filesystem::file_size(out, ec) > 0 &&
         (input.empty() || std::filesystem::last_write_time(out) >= std::filesystem::last_write_time(input));
}

// A net newer than the installed SUMO is refused before SUMO misreads it, or converted with the
// installed netconvert into `dir` where the options allow: returns the net to run.
std::filesystem::path readable_net(const std::filesystem::path& net, const std::filesystem::path& dir, const NetOptions& options,
                                   std::filesystem::path& rebuilt_from) {
  std::string version;
  try {
    version = maps::read_sumo_net_version(net);
  } catch (const std::exception& e) {
    throw SimError(e.what());
  }
  // Old nets carry no version, and SUMO reads them: no need to ask SUMO for its own.
  if (version.empty()) return net;
  const std::string sumo = installed_sumo_version();
  try {
    check_net_version(net, version, sumo);
    return net;
  } catch (const SimError& e) {
    if (!options.rebuild_net) throw SimError(std::string(e.what()) + ", or give --rebuild-net to convert it into the work directory");
  }
  prepare(dir);
  std::string stem = net.filename().string();
  if (stem.ends_with(".net.xml")) stem.resize(stem.size() - 8);
  const auto out = dir / (stem + ".rebuilt.net.xml");
  rebuilt_from = net;
  if (up_to_date(out, net)) {
    spdlog::warn("event=net_rebuilt net={} net_version={} sumo={} out={} detail=\"converted earlier with the installed netconvert\"",
                 net.string(), version, sumo, out.string());
    return out;
  }
  spdlog::warn("event=net_rebuilt net={} net_version={} sumo={} out={} detail=\"written by a newer netconvert; converted with "
               "the installed one, the original is left as it is\"",
               net.string(), version, sumo, out.string());
  run_tool({"netconvert", "--sumo-net-file", net.string(), "-o", out.string()}, dir / (stem + ".rebuild.log"));
  return out;
}

}  // namespace

ScenarioNet build_grid_net(const std::filesystem::path& dir, const GridSpec& spec) {
  if (spec.blocks < 2 || spec.blocks > 50 || !(spec.block_m >= 20.0) || spec.lanes < 1 || spec.lanes > 4 ||
      !(spec.speed_kmh > 0.0)) {
    throw SimError("grid needs 2-50 junctions per side, blocks of at least 20 m, 1-4 lanes and a positive speed");
  }
  prepare(dir);
  const std::string name = fmt::format("grid{}x{}", spec.blocks, spec.blocks);
  ScenarioNet net{name, dir, dir / (name + ".net.xml"), std::nullopt, {}};
  if (up_to_date(net.net, {})) return net;
  run_tool({"netgenerate", "--grid", "--grid.number", std::to_string(spec.blocks), "--grid.length",
            fmt::format("{}", spec.block_m), "--default.lanenumber", std::to_string(spec.lanes), "--default.speed",
            fmt::format("{:.4f}", spec.speed_kmh / 3.6), "--default-junction-type", "traffic_light",
            "--tls.default-type", "static", "--no-turnarounds", "true", "-o", net.net.string()},
           dir / "netgenerate.log");
  return net;
}

namespace {

// One SUMO state per NEMA phase: a link is green when its movement is served, 'G' when no other
// served movement conflicts with it and 'g' (yield) otherwise; links without a NEMA movement (none
// on a plain grid) stay red.
std::string nema_state(const maps::SignalPlan& plan, const maps::Phase& phase, const std::vector<std::optional<std::size_t>>& link_movement) {
  std::string state(link_movement.size(), 'r');
  for (std::size_t i = 0; i < link_movement.size(); ++i) {
    if (!link_movement[i] || !phase.serves(*link_movement[i])) continue;
    bool yields = false;
    for (std::size_t m = 0; m < plan.movements.size(); ++m) yields = yields || (phase.serves(m) && plan.conflicts(*link_movement[i], m));
    state[i] = yields ? 'g' : 'G';
  }
  return state;
}

// The SUMO program of a NEMA plan: each step's green, then yellow for the links that lose green,
// then all-red for them, before the next step.
std::string nema_tl_logic(const std::string& tls, const maps::SignalPlan& plan,
                          const std::vector<std::optional<std::size_t>>& link_movement) {
  std::string xml = fmt::format("  <tlLogic id=\"{}\" type=\"static\" programID=\"0\" offset=\"0\">\n", tls);
  for (std::size_t k = 0; k < plan.program.size(); ++k) {
    const auto& step = plan.program[k];
    const auto& next = plan.program[(k + 1) % plan.program.size()];
    const std::string green = nema_state(plan, plan.phases[step.phase], link_movement);
    const std::string after = nema_state(plan, plan.phases[next.phase], link_movement);
    std::string yellow = green, red = green;
    for (std::size_t i = 0; i < green.size(); ++i) {
      if (green[i] != 'r' && after[i] == 'r') yellow[i] = 'y', red[i] = 'r';
    }
    xml += fmt::format("    <phase duration=\"{:g}\" state=\"{}\"/>\n", step.green_s, green);
    if (yellow == green) continue;  // the next step keeps every green: no clearance needed
    xml += fmt::format("    <phase duration=\"{:g}\" state=\"{}\"/>\n", plan.yellow_s, yellow);
    xml += fmt::format("    <phase duration=\"{:g}\" state=\"{}\"/>\n", plan.all_red_s, red);
  }
  return xml + "  </tlLogic>\n";
}

}  // namespace

ScenarioNet build_nema_grid_net(const std::filesystem::path& dir, const GridSpec& spec) {
  const ScenarioNet base = build_grid_net(dir, spec);
  const std::string name = fmt::format("nema_grid{}x{}", spec.blocks, spec.blocks);
  ScenarioNet net{name, dir, dir / (name + ".net.xml"), std::nullopt, {}};
  if (up_to_date(net.net, base.net)) return net;
  const maps::SumoNet sumo = maps::read_sumo_net(base.net);
  std::string tll = "<tlLogics>\n";
  for (const maps::SumoTlLogic& logic : sumo.tl_logics) {
    const maps::SumoJunction* junction = sumo.junction(logic.id);
    if (junction == nullptr) throw SimError("grid light '" + logic.id + "' has no junction of that id");
    const auto side_of = [&](const std::string& other) {
      const maps::SumoJunction* j = sumo.junction(other);
      if (j == nullptr) throw SimError("grid edge to an unknown junction '" + other + "'");
      return maps::compass_side(junction->position, j->position);
    };
    std::vector<const maps::SumoConnection*> links;
    std::uint8_t legs = 0;
    for (const maps::SumoConnection& c : sumo.connections) {
      if (c.tl != logic.id || c.link_index < 0) continue;
      if (links.size() <= static_cast<std::size_t>(c.link_index)) links.resize(static_cast<std::size_t>(c.link_index) + 1, nullptr);
      links[static_cast<std::size_t>(c.link_index)] = &c;
      legs |= static_cast<std::uint8_t>(1u << static_cast<int>(side_of(sumo.edge(c.from)->from)));
      legs |= static_cast<std::uint8_t>(1u << static_cast<int>(side_of(sumo.edge(c.to)->to)));
    }
    const maps::SignalPlan plan = maps::make_nema_plan(NodeId{0}, legs);
    std::vector<std::optional<std::size_t>> link_movement(links.size());
    for (std::size_t i = 0; i < links.size(); ++i) {
      if (links[i] == nullptr) continue;
      link_movement[i] = plan.movement_index(side_of(sumo.edge(links[i]->from)->from), side_of(sumo.edge(links[i]->to)->to));
    }
    tll += nema_tl_logic(logic.id, plan, link_movement);
  }
  tll += "</tlLogics>\n";
  const auto tll_file = dir / (name + ".tll.xml");
  std::ofstream tll_out(tll_file, std::ios::trunc);
  tll_out << tll;
  tll_out.close();
  if (!tll_out) throw SimError("cannot write " + tll_file.string());
  run_tool({"netconvert", "--sumo-net-file", base.net.string(), "--tllogic-files", tll_file.string(), "-o", net.net.string()},
           dir / "netconvert_nema.log");
  return net;
}

ScenarioNet build_osm_net(const std::filesystem::path& dir, const std::filesystem::path& osm_file) {
  if (!std::filesystem::exists(osm_file)) throw SimError("OSM file '" + osm_file.string() + "' does not exist");
  prepare(dir);
  std::string name = osm_file.filename().string();
  name = name.substr(0, name.find('.'));
  ScenarioNet net{name, dir, dir / (name + ".net.xml"), std::nullopt, {}};
  if (up_to_date(net.net, osm_file)) return net;
  std::filesystem::path input = osm_file;
  if (osm_file.extension() == ".pbf") {
    input = dir / (name + ".osm");
    run_tool({"osmium", "cat", "--overwrite", "-o", input.string(), osm_file.string()}, dir / "osmium.log");
  }
  run_tool({"netconvert", "--osm-files", input.string(), "--geometry.remove", "--ramps.guess", "--junctions.join",
            "--tls.guess-signals", "--tls.discard-simple", "--tls.join", "--keep-edges.by-vclass", "passenger",
            "--remove-edges.isolated", "--no-turnarounds", "true", "-o", net.net.string()},
           dir / "netconvert.log");
  return net;
}

ScenarioNet build_scenario_net(const std::string& scenario, const std::filesystem::path& dir, const NetOptions& options) {
  if (scenario == "grid") return build_grid_net(dir, GridSpec{});
  if (scenario == "nema-grid") return build_nema_grid_net(dir, GridSpec{});
  const std::filesystem::path file(scenario);
  if (!std::filesystem::exists(file)) {
    throw SimError("--scenario must be grid, a .sumocfg, a .net.xml, or an OSM file (.osm, .osm.gz, .osm.pbf); '" +
                   scenario + "' does not exist");
  }
  const std::string name = file.filename().string();
  if (name.size() > 8 && name.ends_with(".sumocfg")) {
    SumoConfig config = read_sumo_config(file);
    ScenarioNet net{name.substr(0, name.size() - 8), dir, {}, std::nullopt, {}};
    net.net = readable_net(config.net_file, dir, options, net.rebuilt_from);
    prepare(dir);
    net.config = std::move(config);
    return net;
  }
  if (name.size() > 8 && name.ends_with(".net.xml")) {
    ScenarioNet net{name.substr(0, name.size() - 8), dir, {}, std::nullopt, {}};
    net.net = std::filesystem::absolute(readable_net(std::filesystem::absolute(file), dir, options, net.rebuilt_from));
    prepare(dir);
    return net;
  }
  if (name.ends_with(".osm") || name.ends_with(".osm.gz") || name.ends_with(".pbf")) return build_osm_net(dir, file);
  throw SimError("'" + scenario + "' is neither a SUMO .net.xml nor an OSM file (.osm, .osm.gz, .osm.pbf)");
}

std::filesystem::path build_background_demand(const ScenarioNet& net, const DemandSpec& spec) {
  if (!(spec.vehicles_per_hour > 0.0) || !(spec.end_s > 0.0)) {
    throw SimError("background demand needs a positive volume and duration");
  }
  const std::string stem = fmt::format("{}_v{:g}_s{}_e{:g}", net.name, spec.vehicles_per_hour, spec.seed, spec.end_s);
  const auto routes = net.dir / (stem + ".rou.xml");
  if (up_to_date(routes, net.net)) return routes;
  const auto script = sumo_home() / "tools" / "randomTrips.py";
  if (!std::filesystem::exists(script)) {
    throw SimError("randomTrips.py not found at " + script.string() + " (install sumo-tools, or set SUMO_HOME)");
  }
  run_tool({"/usr/bin/python3", script.string(), "-n", net.net.string(), "-o", (net.dir / (stem + ".trips.xml")).string(),
            "-r", routes.string(), "--seed", std::to_string(spec.seed), "--begin", "0", "--end",
            fmt::format("{:g}", spec.end_s), "--period", fmt::format("{:.6f}", 3600.0 / spec.vehicles_per_hour),
            "--fringe-factor", "5", "--min-distance", "300", "--prefix", "bg", "--validate"},
           net.dir / (stem + ".log"));
  return routes;
}

}  // namespace corridor::sim
