// SQLite persistence (WAL) of everything the dispatch service acknowledges: missions, positions,
// route revisions, congestion updates and preemption events, with versioned migrations. Writes
// complete before the caller acknowledges; restart recovery reads them back. WAL checkpoints run
// on a background connection, off the commit path.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <vector>

#include "maps/ids.hpp"
#include "planner/cost_overlay.hpp"
#include "server/dispatch_types.hpp"

struct sqlite3;
struct sqlite3_stmt;

namespace corridor::server {

class StoreError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct MissionRow {
  MissionId id = 0;
  std::string vehicle_id;
  int priority = 1;
  double vmax_kmh = 120.0;
  maps::LatLon destination;
  std::optional<maps::LatLon> origin;
  MissionState state = MissionState::active;
  double created_s = 0;
  double updated_s = 0;
  std::string profile = "ambulance";  // a built-in vehicle profile (planner/vehicle_profile.hpp)
};

struct PositionRow {
  std::string vehicle_id;
  maps::LatLon position;
  std::optional<double> heading_deg;
  double timestamp_s = 0;
  std::optional<double> speed_mps;
  std::string source = "gps";
};

struct CongestionRow {
  EdgeId edge;
  planner::EdgeCondition condition;
  std::optional<double> expires_at_s;
};

// One call on a field signal controller (ntcip::CallRecord), with the vehicle of its first mission.
struct SignalCallRow {
  std::uint64_t id = 0;
  NodeId signal;
  std::string controller;
  std::optional<MissionId> mission;  // the highest-priority mission it served
  std::string vehicle_id;
  std::vector<MissionId> missions;
  int priority = 0;
  std::string kind;  // preempt, phase_control
  std::uint32_t preempt = 0;
  std::string approach;
  double request_s = 0.0;
  std::optional<double> grant_s;
  std::optional<double> release_s;
  std::optional<double> clear_s;
  std::string outcome;
};

enum class Durability {
  process_crash,  // synchronous=NORMAL: survives kill -9, not power loss
  power_loss,     // synchronous=FULL
};

class Store {
 public:
  // Opens or creates the database and applies pending migrations. Throws StoreError, also when
  // another server has the database open.
  explicit Store(const std::filesystem::path& file, Durability durability = Durability::process_crash);
  ~Store();
  Store(const Store&) = delete;
  Store& operator=(const Store&) = delete;

  [[nodiscard]] int schema_version() const;

  // Groups writes into one atomic commit.
  class Transaction {
   public:
    explicit Transaction(Store& store);
    ~Transaction();
    Transaction(const Transaction&) = delete;
    Transaction& operator=(const Transaction&) = delete;
    void commit();

   private:
    Store& store_;
    bool done_ = false;
  };

  // Under the row's own id (the service numbers missions, so it knows the id before storing).
  void insert_mission(const MissionRow& row);
  void update_mission_state(MissionId id, MissionState state, double time_s);
  // Stored as received, with what the tracker made of it; only a followed report becomes the
  // vehicle's latest position.
  void insert_position(const PositionReport& report, std::optional<MissionId> mission, double received_s,
                       const PositionMatch& match = {});
  void insert_route_revision(MissionId mission, std::uint32_t revision, const std::string& reason, double eta_s,
                             double length_m, const std::string& geometry_json, double time_s);
  void insert_congestion(EdgeId edge, const planner::EdgeCondition& condition, std::optional<double> expires_at_s,
                         double time_s);
  void insert_preemption_event(const preemption::PreemptionEvent& event);
  // A call record as it stands now (a later write of the same id replaces it).
  void upsert_signal_call(const SignalCallRow& row);

  [[nodiscard]] std::vector<MissionRow> missions(std::optional<MissionState> state) const;
  [[nodiscard]] std::optional<PositionRow> last_position(const std::string& vehicle_id) const;
  // Every vehicle's latest followed position, by vehicle id: what GET /v1/vehicles showed before a
  // restart, missions or not.
  [[nodiscard]] std::vector<PositionRow> last_positions() const;
  // A mission's route revisions, oldest first.
  [[nodiscard]] std::vector<RouteRevisionView> route_revisions(MissionId mission) const;
  // The latest condition of every edge whose latest update has not expired by `now_s`.
  [[nodiscard]] std::vector<CongestionRow> congestion_in_force(double now_s) const;
  [[nodiscard]] std::size_t count(const std::string& table) const;
  // Call records, newest first, of one signal or one mission (or all), at most `limit`.
  [[nodiscard]] std::vector<SignalCallRow> signal_calls(std::optional<NodeId> signal, std::optional<MissionId> mission,
                                                        std::size_t limit) const;

 private:
  void exec(const std::string& sql) const;
  void migrate();
  // Write statements are prepared once; writes come from one thread at a time (the commit queue).
  sqlite3_stmt* cached(const char* sql);

  class Checkpointer;

  sqlite3* db_ = nullptr;
  int lock_fd_ = -1;
  std::unique_ptr<Checkpointer> checkpointer_;
  std::unordered_map<const char*, sqlite3_stmt*> statements_;  // keyed by the SQL literal's address
  std::filesystem::path file_;
};

}  // namespace corridor::server
