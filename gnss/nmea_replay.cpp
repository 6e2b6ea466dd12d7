#include "gnss/nmea_replay.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <signal.h>
#include <spdlog/spdlog.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cctype>
#include <chrono>
#include <fstream>
#include <thread>
#include <vector>

namespace corridor::gnss {
namespace {

int hex(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  return -1;
}

int free_tcp_port() {
  const int s = socket(AF_INET, SOCK_STREAM, 0);
  if (s < 0) return -1;
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t len = sizeof a;
  int port = -1;
  if (bind(s, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0 && getsockname(s, reinterpret_cast<sockaddr*>(&a), &len) == 0) {
    port = ntohs(a.sin_port);
  }
  close(s);
  return port;
}

bool listening(int port) {
  const int s = socket(AF_INET, SOCK_STREAM, 0);
  if (s < 0) return false;
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  const bool ok = ::connect(s, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
  close(s);
  return ok;
}

std::string gpsd_binary() {
  for (const char* p : {"/usr/sbin/gpsd", "/usr/local/sbin/gpsd", "/usr/bin/gpsd"}) {
    if (access(p, X_OK) == 0) return p;
  }
  return {};
}

}  // namespace

NmeaLogCheck check_nmea_log(std::string_view text) {
  NmeaLogCheck c;
  std::size_t i = 0;
  while (i < text.size()) {
    std::size_t j = text.find('\n', i);
    if (j == std::string_view::npos) j = text.size();
    std::string_view line = text.substr(i, j - i);
    i = j + 1;
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.remove_suffix(1);
    if (line.empty()) continue;
    ++c.lines;
    if (line.front() != '$' && line.front() != '!') {
      ++c.other;
      continue;
    }
    ++c.sentences;
    const auto star = line.rfind('*');
    if (star == std::string_view::npos || star + 3 != line.size()) continue;  // no checksum: gpsd judges
    const int hi = hex(line[star + 1]), lo = hex(line[star + 2]);
    if (hi < 0 || lo < 0) continue;
    unsigned sum = 0;
    for (std::size_t k = 1; k < star; ++k) sum ^= static_cast<unsigned char>(line[k]);
    if (sum != static_cast<unsigned>(hi * 16 + lo)) ++c.bad_checksums;
  }
  return c;
}

NmeaReplay::NmeaReplay(const std::filesystem::path& log) {
  std::ifstream in(log, std::ios::binary);
  if (!in) throw GnssError("NMEA log not found: '" + log.string() + "'");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  check_ = check_nmea_log(text);
  if (check_.sentences == 0) {
    throw GnssError("'" + log.string() + "' holds no NMEA sentence (lines starting with $, such as $GPRMC): is it an NMEA log?");
  }
  if (check_.sentences == check_.bad_checksums) throw GnssError("'" + log.string() + "': no NMEA sentence has a right checksum");
  const std::string gpsd = gpsd_binary();
  if (gpsd.empty()) throw GnssError("gpsd is not installed (Debian package gpsd): it decodes the NMEA log");
  // gpsd runs as its own user once started: the log's copy must be readable to it.
  std::string pattern = (std::filesystem::temp_directory_path() / "corridor-nmea-XXXXXX").string();
  std::vector<char> buf(pattern.begin(), pattern.end());
  buf.push_back('\0');
  if (mkdtemp(buf.data()) == nullptr) throw GnssError("cannot make a temporary directory for the NMEA log");
  dir_ = buf.data();
  chmod(dir_.c_str(), 0755);
  const auto copy = dir_ / "log.nmea";
  std::filesystem::copy_file(log, copy);
  chmod(copy.c_str(), 0644);
  const int port = free_tcp_port();
  if (port < 0) throw GnssError("no free TCP port for a private gpsd");
  const std::string port_text = std::to_string(port);
  gpsd_pid_ = fork();
  if (gpsd_pid_ < 0) throw GnssError("cannot start gpsd");
  if (gpsd_pid_ == 0) {
    // -N: in the foreground, so that it is ours to stop; -b: read-only, nothing written to the "device".
    const int null = ::open("/dev/null", O_WRONLY);
    if (null >= 0) {
      dup2(null, STDOUT_FILENO);
      dup2(null, STDERR_FILENO);
    }
    execl(gpsd.c_str(), gpsd.c_str(), "-N", "-b", "-S", port_text.c_str(), copy.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  for (int i = 0; i < 100 && !listening(port); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  GpsdSourceOptions options;
  options.reconnect = false;
  options.idle_timeout_s = 2.0;  // gpsd reads a file at once: silence is its end
  try {
    source_ = std::make_unique<GpsdSource>("127.0.0.1", port_text, options);
  } catch (const GnssError&) {
    kill(gpsd_pid_, SIGTERM);
    waitpid(gpsd_pid_, nullptr, 0);
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
    throw GnssError("gpsd did not start on the NMEA log (port " + port_text + ")");
  }
  spdlog::info("event=nmea_replay log={} sentences={} bad_checksums={} other_lines={}", log.string(), check_.sentences,
               check_.bad_checksums, check_.other);
}

NmeaReplay::~NmeaReplay() {
  source_.reset();
  if (gpsd_pid_ > 0) {
    kill(gpsd_pid_, SIGTERM);
    waitpid(gpsd_pid_, nullptr, 0);
  }
  std::error_code ec;
  std::filesystem::remove_all(dir_, ec);
}

std::optional<GnssReport> NmeaReplay::next() { return source_->next(); }

}  // namespace corridor::gnss
