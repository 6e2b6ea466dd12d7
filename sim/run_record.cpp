#include "sim/run_record.hpp"

#include <fstream>

#include "sim/errors.hpp"
#include "sim/result_json.hpp"

namespace corridor::sim {

const char* to_string(RunStatus s) { return s == RunStatus::ok ? "ok" : "failed"; }

nlohmann::json to_json_record(const RunRecord& r) {
  nlohmann::json j = r.result;
  j["scenario"] = r.scenario;
  j["with_ev"] = r.with_ev;
  j["routing"] = to_string(r.routing);
  j["signals"] = to_string(r.signals);
  j["volume"] = r.volume;
  j["demand_scale"] = r.demand_scale;
  j["seed"] = r.seed;
  j["ev_from"] = r.ev_from;
  j["ev_to"] = r.ev_to;
  j["ev_depart_s"] = r.ev_depart_s;
  j["vicinity"] = r.vicinity;
  j["inject_on_route"] = r.inject_on_route;
  j["ev_count"] = r.evs;
  j["status"] = to_string(r.status);
  if (r.status == RunStatus::failed) j["error"] = r.failure;
  return j;
}

RunRecord record_from_json(const nlohmann::json& j, const std::string& source) {
  if (!j.is_object()) throw SimError(source + ": not a run record");
  // A failed run without its identity (a child that died before it knew it) cannot be a row.
  if (j.contains("error") && !j.contains("scenario")) {
    throw SimError(source + ": the run failed: " + (j["error"].is_string() ? j["error"].get<std::string>() : j["error"].dump()));
  }
  try {
    RunRecord r;
    r.scenario = j.at("scenario").get<std::string>();
    r.with_ev = j.at("with_ev").get<bool>();
    const auto routing = parse_ev_routing(j.at("routing").get<std::string>());
    if (!routing) throw SimError("unknown routing '" + j.at("routing").get<std::string>() + "'");
    r.routing = *routing;
    const auto signals = parse_ev_signals(j.at("signals").get<std::string>());
    if (!signals) throw SimError("unknown signals '" + j.at("signals").get<std::string>() + "'");
    r.signals = *signals;
    r.volume = j.at("volume").get<double>();
    r.demand_scale = j.at("demand_scale").get<double>();
    r.seed = j.at("seed").get<std::uint64_t>();
    r.ev_from = j.value("ev_from", std::string{});
    r.ev_to = j.value("ev_to", std::string{});
    r.ev_depart_s = j.at("ev_depart_s").get<double>();
    r.vicinity = j.value("vicinity", true);
    r.inject_on_route = j.value("inject_on_route", false);
    r.evs = j.value("ev_count", std::uint32_t{1});
    const std::string status = j.value("status", std::string(j.contains("error") ? "failed" : "ok"));
    if (status != "ok" && status != "failed") throw SimError("unknown status '" + status + "'");
    r.status = status == "ok" ? RunStatus::ok : RunStatus::failed;
    if (r.status == RunStatus::failed) {
      r.failure = j.contains("error") && j["error"].is_string() ? j["error"].get<std::string>() : std::string("unknown");
      return r;
    }
    r.result = j.get<ClosedLoopResult>();
    return r;
  } catch (const nlohmann::json::exception& e) {
    throw SimError(source + ": not a run record (" + e.what() + ")");
  } catch (const SimError& e) {
    throw SimError(source + ": " + e.what());
  }
}

RunRecord failed_run(RunRecord identity, std::string why) {
  identity.status = RunStatus::failed;
  identity.failure = std::move(why);
  identity.result = {};
  return identity;
}

void write_record(const std::filesystem::path& file, const RunRecord& r) {
  std::error_code ec;
  if (file.has_parent_path()) std::filesystem::create_directories(file.parent_path(), ec);
  const auto tmp = file.string() + ".tmp";
  {
    std::ofstream out(tmp, std::ios::trunc | std::ios::binary);
    out << to_json_record(r).dump(2) << '\n';
    if (!out) throw SimError("cannot write " + tmp);
  }
  std::filesystem::rename(tmp, file, ec);
  if (ec) throw SimError("cannot write " + file.string() + ": " + ec.message());
}

}  // namespace corridor::sim
