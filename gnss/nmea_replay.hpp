// A recorded NMEA 0183 log read as a live receiver is: through gpsd, the parser every receiver's
// sentences go through, on a private gpsd started for the log, so that a recording and a receiver
// are decoded alike (checksums, talkers, what each sentence carries). gpsd reads the file at once;
// the fixes keep the receiver's own times.
#pragma once

#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "gnss/gpsd_source.hpp"

namespace corridor::gnss {

// What a log holds before gpsd sees it: lines that look like NMEA sentences, and of those the ones
// whose checksum is right. A file that holds none is not an NMEA log.
struct NmeaLogCheck {
  std::size_t lines = 0;
  std::size_t sentences = 0;      // "$..." or "!..." lines
  std::size_t bad_checksums = 0;  // with a *hh that does not match
  std::size_t other = 0;          // neither
};
[[nodiscard]] NmeaLogCheck check_nmea_log(std::string_view text);

class NmeaReplay {
 public:
  // Throws GnssError when the file is missing, holds no NMEA sentence, or gpsd cannot be started.
  explicit NmeaReplay(const std::filesystem::path& log);
  ~NmeaReplay();
  NmeaReplay(const NmeaReplay&) = delete;
  NmeaReplay& operator=(const NmeaReplay&) = delete;

  // The log's next epoch, nullopt at its end.
  std::optional<GnssReport> next();
  [[nodiscard]] const NmeaLogCheck& check() const { return check_; }

 private:
  NmeaLogCheck check_;
  std::filesystem::path dir_;  // the log's copy, readable by gpsd's own user
  int gpsd_pid_ = -1;
  std::unique_ptr<GpsdSource> source_;
};

}  // namespace corridor::gnss
