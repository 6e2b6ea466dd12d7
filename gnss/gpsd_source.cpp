#include "gnss/gpsd_source.hpp"

#include <gps.h>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <deque>
#include <thread>

namespace corridor::gnss {

struct GpsdSource::Connection {
  gps_data_t data{};
  bool open = false;
  ~Connection() {
    if (open) {
      (void)gps_stream(&data, WATCH_DISABLE, nullptr);
      gps_close(&data);
    }
  }
};

namespace {

using Clock = std::chrono::steady_clock;

std::optional<double> value(double v) { return std::isfinite(v) ? std::optional<double>(v) : std::nullopt; }

GnssReport report_of(const gps_fix_t& f) {
  GnssReport r;
  switch (f.mode) {
    case MODE_NO_FIX: r.mode = FixMode::none; break;
    case MODE_2D: r.mode = FixMode::two_d; break;
    case MODE_3D: r.mode = FixMode::three_d; break;
    default: r.mode = FixMode::not_seen; break;
  }
  if (f.time.tv_sec != 0) r.time_s = static_cast<double>(f.time.tv_sec) + static_cast<double>(f.time.tv_nsec) * 1e-9;
  r.lat_deg = value(f.latitude);
  r.lon_deg = value(f.longitude);
  r.track_deg = value(f.track);
  r.speed_mps = value(f.speed);
  r.eph_m = value(f.eph);
  r.epx_m = value(f.epx);
  r.epy_m = value(f.epy);
  return r;
}

bool is_tpv(const char* message) { return std::strncmp(message, "{\"class\":\"TPV\"", 14) == 0; }

}  // namespace

std::optional<GnssReport> decode_gpsd_message(std::string message) {
  gps_data_t data{};
  // libgps parses in place and stops at the NUL. Its parser (3.22) never returns on some malformed
  // objects, such as {"class":"TPV""class":"TPV" (found by gnss_fuzzer), so only well-formed JSON reaches it.
  if (!is_tpv(message.c_str()) || !nlohmann::json::accept(message)) return std::nullopt;
  if (gps_unpack(message.data(), &data) != 0) return std::nullopt;
  // A TPV always carries its mode.
  if ((data.set & MODE_SET) == 0) return std::nullopt;
  return report_of(data.fix);
}

GpsdSource::GpsdSource(std::string host, std::string port, GpsdSourceOptions options)
    : host_(std::move(host)), port_(std::move(port)), options_(options) {
  if (!connect()) throw GnssError("cannot connect to gpsd at " + host_ + ":" + port_ + " (" + gps_errstr(errno) + ")");
}

GpsdSource::~GpsdSource() = default;

bool GpsdSource::connect() {
  auto c = std::make_unique<Connection>();
  if (gps_open(host_.c_str(), port_.c_str(), &c->data) != 0) return false;
  c->open = true;
  (void)gps_stream(&c->data, WATCH_ENABLE | WATCH_JSON, nullptr);
  conn_ = std::move(c);
  return true;
}

std::optional<GnssReport> GpsdSource::read_one(double wait_s) {
  if (!conn_) return std::nullopt;
  // gps_waiting takes microseconds; it also returns true when the connection has closed.
  if (!gps_waiting(&conn_->data, static_cast<int>(wait_s * 1e6))) return std::nullopt;
  char message[10240];
  errno = 0;
  const int rc = gps_read(&conn_->data, message, sizeof message);
  if (rc == -1) {
    spdlog::warn("event=gpsd_disconnected host={} port={} errno={}", host_, port_, errno);
    conn_.reset();
    return std::nullopt;
  }
  if (rc == 0 || (conn_->data.set & PACKET_SET) == 0) return std::nullopt;
  // Other classes add to `set` rather than replace it: a TPV is told by its message.
  if (!is_tpv(message)) return std::nullopt;
  return report_of(conn_->data.fix);
}

std::optional<GnssReport> GpsdSource::next() {
  if (!ended_.empty()) {
    std::optional<GnssReport> last = std::exchange(held_, std::nullopt);
    return last;
  }
  auto last_report = Clock::now();
  double backoff_s = 0.25;
  for (;;) {
    const double idle_s = std::chrono::duration<double>(Clock::now() - last_report).count();
    if (idle_s > options_.idle_timeout_s) {
      ended_ = conn_ ? "idle" : "disconnected";
      return std::exchange(held_, std::nullopt);
    }
    if (!conn_) {
      if (!options_.reconnect) {
        ended_ = "disconnected";
        return std::exchange(held_, std::nullopt);
      }
      std::this_thread::sleep_for(std::chrono::duration<double>(backoff_s));
      backoff_s = std::min(4.0, backoff_s * 2.0);
      if (connect()) {
        ++reconnects_;
        spdlog::info("event=gpsd_reconnected host={} port={}", host_, port_);
      }
      continue;
    }
    std::optional<GnssReport> r = read_one(0.5);
    if (!r) continue;
    last_report = Clock::now();
    backoff_s = 0.25;
    // One report per epoch: gpsd may send an epoch twice (after a dropped sentence), the later
    // one fuller; a report without a time is its own.
    if (held_ && held_->time_s && r->time_s && *held_->time_s == *r->time_s) {
      ++duplicates_;
      if (r->track_deg || !held_->track_deg) held_ = r;
      continue;
    }
    std::optional<GnssReport> out = std::exchange(held_, r);
    if (out) return out;
  }
}

}  // namespace corridor::gnss
