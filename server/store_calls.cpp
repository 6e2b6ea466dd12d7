// The store's call records of field signal controllers (table signal_calls, schema v5).
#include <nlohmann/json.hpp>

#include "server/sqlite_statement.hpp"
#include "server/store.hpp"

namespace corridor::server {

void Store::upsert_signal_call(const SignalCallRow& r) {
  Statement s(cached("INSERT OR REPLACE INTO signal_calls(id, signal, controller, mission_id, vehicle_id, missions, priority, kind, "
                     "preempt, approach, request_s, grant_s, release_s, clear_s, outcome) VALUES (?,?,?,?,?,?,?,?,?,?,?,?,?,?,?)"));
  s.bind(1, static_cast<std::int64_t>(r.id)).bind(2, static_cast<std::int64_t>(r.signal.v)).bind(3, r.controller);
  if (r.mission) {
    s.bind(4, static_cast<std::int64_t>(*r.mission));
  } else {
    s.bind(4, std::optional<double>{});
  }
  s.bind(5, r.vehicle_id).bind(6, nlohmann::json(r.missions).dump()).bind(7, static_cast<std::int64_t>(r.priority)).bind(8, r.kind);
  s.bind(9, static_cast<std::int64_t>(r.preempt)).bind(10, r.approach).bind(11, r.request_s).bind(12, r.grant_s).bind(13, r.release_s);
  s.bind(14, r.clear_s).bind(15, r.outcome).step();
}

std::vector<SignalCallRow> Store::signal_calls(std::optional<NodeId> signal, std::optional<MissionId> mission, std::size_t limit) const {
  const char* sql = signal    ? "SELECT id, signal, controller, mission_id, vehicle_id, missions, priority, kind, preempt, approach, request_s, "
                                "grant_s, release_s, clear_s, outcome FROM signal_calls WHERE signal = ? ORDER BY id DESC LIMIT ?"
                    : mission ? "SELECT id, signal, controller, mission_id, vehicle_id, missions, priority, kind, preempt, approach, request_s, "
                                "grant_s, release_s, clear_s, outcome FROM signal_calls WHERE mission_id = ? ORDER BY id DESC LIMIT ?"
                              : "SELECT id, signal, controller, mission_id, vehicle_id, missions, priority, kind, preempt, approach, request_s, "
                                "grant_s, release_s, clear_s, outcome FROM signal_calls WHERE ? IS NULL ORDER BY id DESC LIMIT ?";
  Statement s(db_, sql);
  if (signal) {
    s.bind(1, static_cast<std::int64_t>(signal->v));
  } else if (mission) {
    s.bind(1, static_cast<std::int64_t>(*mission));
  } else {
    s.bind(1, std::optional<double>{});
  }
  s.bind(2, static_cast<std::int64_t>(limit));
  std::vector<SignalCallRow> out;
  while (s.step()) {
    SignalCallRow r;
    r.id = static_cast<std::uint64_t>(s.integer(0));
    r.signal = NodeId{static_cast<std::uint32_t>(s.integer(1))};
    r.controller = s.text(2);
    if (!s.null(3)) r.mission = static_cast<MissionId>(s.integer(3));
    r.vehicle_id = s.text(4);
    const auto missions = nlohmann::json::parse(s.text(5), nullptr, false);
    if (missions.is_array()) {
      for (const auto& m : missions) {
        if (m.is_number_unsigned()) r.missions.push_back(m.get<MissionId>());
      }
    }
    r.priority = static_cast<int>(s.integer(6));
    r.kind = s.text(7);
    r.preempt = static_cast<std::uint32_t>(s.integer(8));
    r.approach = s.text(9);
    r.request_s = s.real(10);
    r.grant_s = s.optional_real(11);
    r.release_s = s.optional_real(12);
    r.clear_s = s.optional_real(13);
    r.outcome = s.text(14);
    out.push_back(std::move(r));
  }
  return out;
}

}  // namespace corridor::server
