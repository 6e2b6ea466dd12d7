// Reports from a GNSS receiver through gpsd, with libgps: the TPV stream of one gpsd, read as it
// comes, each epoch once (gpsd can report an epoch twice; the later, fuller report wins), the
// connection kept up (a gpsd that goes away is reconnected with backoff), and silence noticed.
#pragma once

#include <chrono>
#include <memory>
#include <optional>
#include <string>

#include "gnss/gnss_report.hpp"

namespace corridor::gnss {

class GnssError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct GpsdSourceOptions {
  // Reconnect when gpsd goes away: a receiver's daemon restarts, a cable is plugged back.
  bool reconnect = true;
  // No report for this long ends the stream (the receiver or its daemon is gone).
  double idle_timeout_s = 10.0;
};

// One message of gpsd's JSON protocol decoded by libgps as a live stream is: the report when it is a
// TPV, nullopt for every other class and for what libgps cannot read.
[[nodiscard]] std::optional<GnssReport> decode_gpsd_message(std::string message);

class GpsdSource {
 public:
  // Connects at once; throws GnssError when gpsd cannot be reached.
  GpsdSource(std::string host, std::string port, GpsdSourceOptions options = {});
  ~GpsdSource();
  GpsdSource(const GpsdSource&) = delete;
  GpsdSource& operator=(const GpsdSource&) = delete;

  // The next epoch's report, or nullopt when the stream ended (idle past the timeout, or gpsd gone
  // and not coming back). Blocks.
  std::optional<GnssReport> next();
  // Why the stream ended: "idle", "disconnected", or empty while it runs.
  [[nodiscard]] const std::string& ended() const { return ended_; }
  [[nodiscard]] std::size_t reconnects() const { return reconnects_; }
  [[nodiscard]] std::size_t duplicates() const { return duplicates_; }

  struct Connection;

 private:
  bool connect();
  std::optional<GnssReport> read_one(double wait_s);

  std::string host_, port_;
  GpsdSourceOptions options_;
  std::unique_ptr<Connection> conn_;
  std::optional<GnssReport> held_;  // the latest report of the epoch not yet given out
  std::string ended_;
  std::size_t reconnects_ = 0, duplicates_ = 0;
};

}  // namespace corridor::gnss
