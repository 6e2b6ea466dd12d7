#include "server/store.hpp"

#include "server/sqlite_statement.hpp"

#include <fcntl.h>
#include <spdlog/spdlog.h>
#include <sqlite3.h>
#include <sys/file.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <mutex>
#include <thread>

namespace corridor::server {
namespace {

// Each entry moves the schema one version up; never edit a released entry, append a new one.
constexpr std::array<const char*, 5> kMigrations{
    R"sql(
    CREATE TABLE missions (
      id INTEGER PRIMARY KEY AUTOINCREMENT,
      vehicle_id TEXT NOT NULL,
      priority INTEGER NOT NULL,
      vmax_kmh REAL NOT NULL,
      dest_lat REAL NOT NULL, dest_lon REAL NOT NULL,
      origin_lat REAL, origin_lon REAL,
      state TEXT NOT NULL,
      created_s REAL NOT NULL,
      updated_s REAL NOT NULL);
    CREATE INDEX missions_state ON missions(state);
    CREATE TABLE positions (
      id INTEGER PRIMARY KEY AUTOINCREMENT,
      vehicle_id TEXT NOT NULL,
      mission_id INTEGER,
      lat REAL NOT NULL, lon REAL NOT NULL,
      heading_deg REAL, speed_mps REAL, hdop REAL,
      timestamp_s REAL NOT NULL,
      source TEXT NOT NULL,
      received_s REAL NOT NULL);
    CREATE INDEX positions_vehicle ON positions(vehicle_id, id);
    CREATE TABLE route_revisions (
      mission_id INTEGER NOT NULL,
      revision INTEGER NOT NULL,
      reason TEXT NOT NULL,
      eta_s REAL NOT NULL,
      length_m REAL NOT NULL,
      geometry TEXT NOT NULL,
      created_s REAL NOT NULL,
      PRIMARY KEY (mission_id, revision));
    CREATE TABLE congestion (
      id INTEGER PRIMARY KEY AUTOINCREMENT,
      edge INTEGER NOT NULL,
      factor REAL,
      queue_delay_s REAL NOT NULL,
      expires_at_s REAL,
      created_s REAL NOT NULL);
    CREATE INDEX congestion_edge ON congestion(edge, id);
    CREATE TABLE preemption_events (
      id INTEGER PRIMARY KEY AUTOINCREMENT,
      mission_id INTEGER NOT NULL,
      node INTEGER NOT NULL,
      kind TEXT NOT NULL,
      detail TEXT NOT NULL,
      time_s REAL NOT NULL);
    )sql",
    // v2: the index on positions(vehicle_id, id) made every position write touch that vehicle's own
    // index leaf, a WAL frame per vehicle per transaction. The latest position of each vehicle is
    // all that is looked up by vehicle, and a small table of those stays on a few hot pages.
    R"sql(
    CREATE TABLE vehicle_last_position (
      vehicle_id TEXT PRIMARY KEY,
      position_id INTEGER NOT NULL) WITHOUT ROWID;
    INSERT INTO vehicle_last_position(vehicle_id, position_id) SELECT vehicle_id, MAX(id) FROM positions GROUP BY vehicle_id;
    DROP INDEX positions_vehicle;
    )sql",
    // v3: what the vehicle tracker made of each report (followed, stale, duplicate, outlier,
    // low_accuracy) and where the map matcher put it.
    R"sql(
    ALTER TABLE positions ADD COLUMN disposition TEXT NOT NULL DEFAULT 'followed';
    ALTER TABLE positions ADD COLUMN edge INTEGER;
    ALTER TABLE positions ADD COLUMN offset_m REAL;
    ALTER TABLE positions ADD COLUMN match_confidence REAL;
    )sql",
    // v4: the vehicle profile a mission plans with (missions stored before it were ambulances).
    R"sql(
    ALTER TABLE missions ADD COLUMN profile TEXT NOT NULL DEFAULT 'ambulance';
    )sql",
    // v5: call records of the field controllers (store_calls.cpp), as field systems keep them.
    R"sql(
    CREATE TABLE signal_calls (
      id INTEGER PRIMARY KEY,
      signal INTEGER NOT NULL,
      controller TEXT NOT NULL,
      mission_id INTEGER,
      vehicle_id TEXT,
      missions TEXT NOT NULL,
      priority INTEGER NOT NULL,
      kind TEXT NOT NULL,
      preempt INTEGER NOT NULL,
      approach TEXT NOT NULL,
      request_s REAL NOT NULL,
      grant_s REAL,
      release_s REAL,
      clear_s REAL,
      outcome TEXT NOT NULL);
    CREATE INDEX signal_calls_signal ON signal_calls(signal, id);
    CREATE INDEX signal_calls_mission ON signal_calls(mission_id, id);
    )sql",
};

}  // namespace

// Copies the WAL back into the database file on its own connection and thread, so that no commit
// waits for a checkpoint's fsync. PASSIVE checkpoints never block the writer, but under sustained
// load the writer never finds the WAL fully copied, so SQLite never rewinds it. Past the hard limit
// the writer itself runs a RESTART between two transactions, once no PASSIVE is running: a short
// stall, since PASSIVE copied the bulk, and a bound that holds however busy the machine is (a
// RESTART from this thread would poll for the write lock and could lose to a busy writer for long).
class Store::Checkpointer {
 public:
  static constexpr int kCheckpointFrames = 1000;  // SQLite's own auto-checkpoint threshold
  static constexpr int kHardLimitFrames = 4000;  // about 16 MB of WAL

  explicit Checkpointer(const std::filesystem::path& file) {
    if (sqlite3_open_v2(file.c_str(), &db_, SQLITE_OPEN_READWRITE, nullptr) != SQLITE_OK) {
      const std::string why = db_ != nullptr ? sqlite3_errmsg(db_) : "out of memory";
      sqlite3_close(db_);
      throw StoreError("cannot open database '" + file.string() + "' for checkpoints: " + why);
    }
    sqlite3_busy_timeout(db_, 5000);
    // A connection opens the WAL only once it reads the database; until then a checkpoint is a no-op.
    if (sqlite3_exec(db_, "PRAGMA journal_mode=WAL", nullptr, nullptr, nullptr) != SQLITE_OK) {
      const std::string why = sqlite3_errmsg(db_);
      sqlite3_close(db_);
      throw StoreError("cannot open database '" + file.string() + "' for checkpoints: " + why);
    }
    thread_ = std::thread([this] { loop(); });
  }
  ~Checkpointer() {
    {
      std::lock_guard lock(mutex_);
      stopping_ = true;
    }
    cv_.notify_all();
    thread_.join();
    sqlite3_close(db_);
  }
  Checkpointer(const Checkpointer&) = delete;
  Checkpointer& operator=(const Checkpointer&) = delete;

  // Called by SQLite on the writer's thread after each commit.
  static int on_commit(void* self, sqlite3* writer, const char*, int wal_frames) {
    auto* c = static_cast<Checkpointer*>(self);
    if (wal_frames > kHardLimitFrames) {
      c->restart(writer, wal_frames);
    } else if (wal_frames >= kCheckpointFrames) {
      c->request();
    }
    return SQLITE_OK;
  }

 private:
  void request() {
    {
      std::lock_guard lock(mutex_);
      wanted_ = true;
    }
    cv_.notify_all();
  }
  void restart(sqlite3* writer, int wal_frames) {
    {
      // No new PASSIVE starts, and the one running finishes first: it copies the bulk. Waiting for
      // it here, rather than leaving the RESTART to a later commit, is what bounds the WAL when the
      // checkpoint thread is starved: a busy writer could otherwise commit past every retry.
      std::unique_lock lock(mutex_);
      held_ = true;
      cv_.wait(lock, [&] { return !running_; });
    }
    spdlog::debug("event=wal_restart_checkpoint wal_frames={}", wal_frames);
    int frames = 0;
    int copied = 0;
    if (sqlite3_wal_checkpoint_v2(writer, nullptr, SQLITE_CHECKPOINT_RESTART, &frames, &copied) != SQLITE_OK) {
      spdlog::warn("event=checkpoint_failed mode=restart error=\"{}\"", sqlite3_errmsg(writer));
    }
    {
      std::lock_guard lock(mutex_);
      held_ = false;
    }
    cv_.notify_all();
  }
  void loop() {
    std::unique_lock lock(mutex_);
    for (;;) {
      cv_.wait(lock, [&] { return stopping_ || (wanted_ && !held_); });
      if (stopping_) return;
      wanted_ = false;
      running_ = true;
      lock.unlock();
      int wal_frames = 0;
      int copied = 0;
      const int rc = sqlite3_wal_checkpoint_v2(db_, nullptr, SQLITE_CHECKPOINT_PASSIVE, &wal_frames, &copied);
      if (rc != SQLITE_OK && rc != SQLITE_BUSY) spdlog::warn("event=checkpoint_failed mode=passive error=\"{}\"", sqlite3_errmsg(db_));
      lock.lock();
      running_ = false;
      cv_.notify_all();  // a writer may wait to RESTART
    }
  }

  sqlite3* db_ = nullptr;
  std::thread thread_;
  std::mutex mutex_;
  std::condition_variable cv_;
  bool wanted_ = false;
  bool running_ = false;  // a PASSIVE checkpoint is copying
  bool held_ = false;     // the writer waits to RESTART
  bool stopping_ = false;
};

Store::Store(const std::filesystem::path& file, Durability durability) : file_(file) {
  // One server owns its database. An advisory lock beside it keeps a second server out; the
  // kernel drops it when the process dies, kill -9 included.
  const std::string lock_path = file.string() + ".lock";
  lock_fd_ = ::open(lock_path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (lock_fd_ < 0) throw StoreError("cannot create lock file '" + lock_path + "': " + std::strerror(errno));
  if (::flock(lock_fd_, LOCK_EX | LOCK_NB) != 0) {
    ::close(lock_fd_);
    throw StoreError("database '" + file.string() + "' is in use by another corridor server (it holds '" + lock_path + "')");
  }
  if (sqlite3_open_v2(file.c_str(), &db_, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_FULLMUTEX, nullptr) !=
      SQLITE_OK) {
    const std::string why = db_ != nullptr ? sqlite3_errmsg(db_) : "out of memory";
    sqlite3_close(db_);
    ::close(lock_fd_);
    throw StoreError("cannot open database '" + file.string() + "': " + why);
  }
  sqlite3_busy_timeout(db_, 5000);
  try {
    exec("PRAGMA journal_mode=WAL");
    exec(durability == Durability::power_loss ? "PRAGMA synchronous=FULL" : "PRAGMA synchronous=NORMAL");
    exec("PRAGMA foreign_keys=ON");
    exec("CREATE TABLE IF NOT EXISTS schema_migrations (version INTEGER PRIMARY KEY, applied_s REAL NOT NULL)");
    migrate();
    // Checkpoints move off the commit path (the hook replaces SQLite's auto-checkpoint).
    checkpointer_ = std::make_unique<Checkpointer>(file);
    sqlite3_wal_hook(db_, &Checkpointer::on_commit, checkpointer_.get());
  } catch (...) {
    sqlite3_close(db_);
    ::close(lock_fd_);
    throw;
  }
}

Store::~Store() {
  sqlite3_wal_hook(db_, nullptr, nullptr);
  checkpointer_.reset();
  for (auto& [sql, stmt] : statements_) sqlite3_finalize(stmt);
  sqlite3_close(db_);  // the last connection checkpoints and removes the WAL
  ::close(lock_fd_);   // releases the lock
}

sqlite3_stmt* Store::cached(const char* sql) {
  auto& stmt = statements_[sql];
  if (stmt == nullptr && sqlite3_prepare_v3(db_, sql, -1, SQLITE_PREPARE_PERSISTENT, &stmt, nullptr) != SQLITE_OK) {
    throw StoreError(std::string("cannot prepare statement: ") + sqlite3_errmsg(db_));
  }
  return stmt;
}

void Store::exec(const std::string& sql) const {
  char* err = nullptr;
  if (sqlite3_exec(db_, sql.c_str(), nullptr, nullptr, &err) != SQLITE_OK) {
    const std::string why = err != nullptr ? err : "unknown error";
    sqlite3_free(err);
    throw StoreError("database '" + file_.string() + "': " + why);
  }
}

int Store::schema_version() const {
  Statement s(db_, "SELECT COALESCE(MAX(version), 0) FROM schema_migrations");
  s.step();
  return static_cast<int>(s.integer(0));
}

void Store::migrate() {
  const int current = schema_version();
  if (current > static_cast<int>(kMigrations.size())) {
    throw StoreError("database '" + file_.string() + "' has schema version " + std::to_string(current) +
                     ", newer than this build (" + std::to_string(kMigrations.size()) + "); refusing to touch it");
  }
  for (int v = current; v < static_cast<int>(kMigrations.size()); ++v) {
    Transaction tx(*this);
    exec(kMigrations[static_cast<std::size_t>(v)]);
    Statement s(db_, "INSERT INTO schema_migrations(version, applied_s) VALUES (?, strftime('%s','now'))");
    s.bind(1, static_cast<std::int64_t>(v + 1)).step();
    tx.commit();
  }
}

Store::Transaction::Transaction(Store& store) : store_(store) { store_.exec("BEGIN IMMEDIATE"); }
Store::Transaction::~Transaction() {
  if (!done_) {
    try {
      store_.exec("ROLLBACK");
    } catch (...) {  // a destructor must not throw; the connection rolls back on close anyway
    }
  }
}
void Store::Transaction::commit() {
  store_.exec("COMMIT");
  done_ = true;
}

void Store::insert_mission(const MissionRow& r) {
  Statement s(cached("INSERT INTO missions(id, vehicle_id, priority, vmax_kmh, dest_lat, dest_lon, origin_lat, origin_lon, "
                     "state, created_s, updated_s, profile) VALUES (?,?,?,?,?,?,?,?,?,?,?,?)"));
  s.bind(1, static_cast<std::int64_t>(r.id)).bind(2, r.vehicle_id).bind(3, static_cast<std::int64_t>(r.priority));
  s.bind(4, r.vmax_kmh).bind(5, r.destination.lat_deg).bind(6, r.destination.lon_deg);
  s.bind(7, r.origin ? std::optional<double>(r.origin->lat_deg) : std::nullopt);
  s.bind(8, r.origin ? std::optional<double>(r.origin->lon_deg) : std::nullopt);
  s.bind(9, std::string(to_string(r.state))).bind(10, r.created_s).bind(11, r.updated_s).bind(12, r.profile);
  s.step();
}

void Store::update_mission_state(MissionId id, MissionState state, double time_s) {
  Statement s(cached("UPDATE missions SET state = ?, updated_s = ? WHERE id = ?"));
  s.bind(1, std::string(to_string(state))).bind(2, time_s).bind(3, static_cast<std::int64_t>(id)).step();
}

void Store::insert_position(const PositionReport& p, std::optional<MissionId> mission, double received_s,
                            const PositionMatch& match) {
  Statement s(cached("INSERT INTO positions(vehicle_id, mission_id, lat, lon, heading_deg, speed_mps, hdop, timestamp_s, "
                     "source, received_s, disposition, edge, offset_m, match_confidence) VALUES (?,?,?,?,?,?,?,?,?,?,?,?,?,?)"));
  s.bind(1, p.vehicle_id);
  s.bind(2, mission ? std::optional<double>(static_cast<double>(*mission)) : std::nullopt);
  s.bind(3, p.position.lat_deg).bind(4, p.position.lon_deg).bind(5, p.heading_deg).bind(6, p.speed_mps).bind(7, p.hdop);
  s.bind(8, p.timestamp_s).bind(9, p.source).bind(10, received_s).bind(11, match.disposition);
  s.bind(12, match.edge ? std::optional<double>(match.edge->v) : std::nullopt);
  s.bind(13, match.edge ? std::optional<double>(match.offset_m) : std::nullopt);
  s.bind(14, match.edge ? std::optional<double>(match.confidence) : std::nullopt).step();
  if (match.disposition != "followed") return;
  Statement latest(cached("INSERT INTO vehicle_last_position(vehicle_id, position_id) VALUES (?, last_insert_rowid()) "
                          "ON CONFLICT(vehicle_id) DO UPDATE SET position_id = excluded.position_id"));
  latest.bind(1, p.vehicle_id).step();
}

void Store::insert_route_revision(MissionId mission, std::uint32_t revision, const std::string& reason, double eta_s,
                                  double length_m, const std::string& geometry_json, double time_s) {
  Statement s(cached("INSERT OR REPLACE INTO route_revisions(mission_id, revision, reason, eta_s, length_m, geometry, "
                     "created_s) VALUES (?,?,?,?,?,?,?)"));
  s.bind(1, static_cast<std::int64_t>(mission)).bind(2, static_cast<std::int64_t>(revision)).bind(3, reason);
  s.bind(4, eta_s).bind(5, length_m).bind(6, geometry_json).bind(7, time_s).step();
}

void Store::insert_congestion(EdgeId edge, const planner::EdgeCondition& c, std::optional<double> expires_at_s,
                              double time_s) {
  Statement s(cached("INSERT INTO congestion(edge, factor, queue_delay_s, expires_at_s, created_s) VALUES (?,?,?,?,?)"));
  // NULL factor stands for a closure (infinity is not a SQL value).
  s.bind(1, static_cast<std::int64_t>(edge.v)).bind(2, std::optional<double>(c.congestion_factor));
  s.bind(3, c.queue_delay_s).bind(4, expires_at_s).bind(5, time_s).step();
}

void Store::insert_preemption_event(const preemption::PreemptionEvent& e) {
  Statement s(cached("INSERT INTO preemption_events(mission_id, node, kind, detail, time_s) VALUES (?,?,?,?,?)"));
  s.bind(1, static_cast<std::int64_t>(e.mission)).bind(2, static_cast<std::int64_t>(e.node.v)).bind(3, e.kind);
  s.bind(4, e.detail).bind(5, e.time_s).step();
}

std::vector<MissionRow> Store::missions(std::optional<MissionState> state) const {
  Statement s(db_, state ? "SELECT id, vehicle_id, priority, vmax_kmh, dest_lat, dest_lon, origin_lat, origin_lon, state, "
                           "created_s, updated_s, profile FROM missions WHERE state = ? ORDER BY id"
                         : "SELECT id, vehicle_id, priority, vmax_kmh, dest_lat, dest_lon, origin_lat, origin_lon, state, "
                           "created_s, updated_s, profile FROM missions ORDER BY id");
  if (state) s.bind(1, std::string(to_string(*state)));
  std::vector<MissionRow> out;
  while (s.step()) {
    MissionRow r;
    r.id = static_cast<MissionId>(s.integer(0));
    r.vehicle_id = s.text(1);
    r.priority = static_cast<int>(s.integer(2));
    r.vmax_kmh = s.real(3);
    r.destination = {s.real(4), s.real(5)};
    if (!s.null(6)) r.origin = maps::LatLon{s.real(6), s.real(7)};
    r.state = mission_state_from(s.text(8)).value_or(MissionState::cancelled);
    r.created_s = s.real(9);
    r.updated_s = s.real(10);
    r.profile = s.text(11);
    out.push_back(std::move(r));
  }
  return out;
}

std::vector<RouteRevisionView> Store::route_revisions(MissionId mission) const {
  Statement s(db_,
              "SELECT revision, reason, created_s, eta_s, length_m, geometry FROM route_revisions "
              "WHERE mission_id = ? ORDER BY revision");
  s.bind(1, static_cast<std::int64_t>(mission));
  std::vector<RouteRevisionView> out;
  while (s.step()) {
    out.push_back({static_cast<std::uint32_t>(s.integer(0)), s.text(1), s.real(2), s.real(3), s.real(4), s.text(5)});
  }
  return out;
}

namespace {

// Each vehicle's latest followed position, one row per vehicle, read by position_row().
constexpr const char* kLastPositions =
    "SELECT v.vehicle_id, p.lat, p.lon, p.heading_deg, p.timestamp_s, p.speed_mps, p.source FROM "
    "vehicle_last_position v JOIN positions p ON p.id = v.position_id";

PositionRow position_row(const Statement& s) {
  return {s.text(0), {s.real(1), s.real(2)}, s.optional_real(3), s.real(4), s.optional_real(5), s.text(6)};
}

}  // namespace

std::optional<PositionRow> Store::last_position(const std::string& vehicle_id) const {
  const std::string sql = std::string(kLastPositions) + " WHERE v.vehicle_id = ?";
  Statement s(db_, sql.c_str());
  s.bind(1, vehicle_id);
  if (!s.step()) return std::nullopt;
  return position_row(s);
}

std::vector<PositionRow> Store::last_positions() const {
  const std::string sql = std::string(kLastPositions) + " ORDER BY v.vehicle_id";
  Statement s(db_, sql.c_str());
  std::vector<PositionRow> out;
  while (s.step()) out.push_back(position_row(s));
  return out;
}

std::vector<CongestionRow> Store::congestion_in_force(double now_s) const {
  Statement s(db_,
              "SELECT c.edge, c.factor, c.queue_delay_s, c.expires_at_s FROM congestion c "
              "JOIN (SELECT edge, MAX(id) AS id FROM congestion GROUP BY edge) latest ON latest.id = c.id "
              "WHERE c.expires_at_s IS NULL OR c.expires_at_s > ? ORDER BY c.edge");
  s.bind(1, now_s);
  std::vector<CongestionRow> out;
  while (s.step()) {
    CongestionRow r;
    r.edge = EdgeId{static_cast<std::uint32_t>(s.integer(0))};
    r.condition.congestion_factor = s.null(1) ? planner::kInfCost : s.real(1);
    r.condition.queue_delay_s = s.real(2);
    r.expires_at_s = s.optional_real(3);
    out.push_back(r);
  }
  return out;
}

std::size_t Store::count(const std::string& table) const {
  for (const char* allowed : {"missions", "positions", "route_revisions", "congestion", "preemption_events", "signal_calls"}) {
    if (table == allowed) {
      Statement s(db_, ("SELECT COUNT(*) FROM " + table).c_str());
      s.step();
      return static_cast<std::size_t>(s.integer(0));
    }
  }
  throw StoreError("unknown table '" + table + "'");
}

}  // namespace corridor::server
