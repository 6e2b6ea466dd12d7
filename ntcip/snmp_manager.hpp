// The central side of SNMP: GETs and SETs to field controllers, v1, v2c or v3 (USM), every one
// asynchronous on one I/O thread, so that a controller that does not answer delays no other and
// never the caller. Net-SNMP's client state (USM keys, engine times, request ids) is process-wide
// and not thread-safe in Debian's build, which is why one thread owns all of it.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "ntcip/controllers_file.hpp"
#include "ntcip/oids.hpp"

namespace corridor::ntcip {

struct SnmpTarget {
  std::string host;
  std::uint16_t port = 161;
  SnmpCredentials credentials;
  double timeout_s = 0.5;  // per try
  int retries = 1;
};

struct SnmpReply {
  enum class Outcome : std::uint8_t {
    ok,            // the controller answered without an error status
    error_status,  // it answered with one (noSuchName, wrongValue, notWritable, ...)
    timeout,       // no answer within the tries (down, unreachable, or a community it drops)
    failure,       // refused by the library (authentication failure, unknown user, cannot send)
  };
  Outcome outcome = Outcome::timeout;
  long error_status = 0;
  long error_index = 0;
  std::string message;
  // The varbinds answered; an exception (noSuchObject, ...) or a non-integer has no value.
  std::vector<std::pair<Oid, std::optional<std::int64_t>>> values;
  [[nodiscard]] bool ok() const { return outcome == Outcome::ok; }
};

class SnmpManager {
 public:
  using Callback = std::function<void(const SnmpReply&)>;
  using SessionId = std::size_t;

  // Starts the I/O thread. One SnmpManager per process.
  SnmpManager();
  ~SnmpManager();
  SnmpManager(const SnmpManager&) = delete;
  SnmpManager& operator=(const SnmpManager&) = delete;

  // A session to one controller, opened on the I/O thread. Thread-safe.
  SessionId open(const SnmpTarget& target);
  // Queued; the callback runs on the I/O thread with the reply (keep it short). Thread-safe.
  void get(SessionId session, std::vector<Oid> oids, Callback done);
  void set(SessionId session, std::vector<std::pair<Oid, std::int64_t>> values, Callback done);

  struct Session;  // one controller's Net-SNMP session

 private:
  void run();
  void post(std::function<void()> task);

  std::mutex mutex_;
  std::deque<std::function<void()>> tasks_;
  std::vector<std::unique_ptr<Session>> sessions_;  // touched on the I/O thread only, after open()
  std::size_t opened_ = 0;
  int wake_[2] = {-1, -1};
  bool stop_ = false;
  std::thread thread_;
};

}  // namespace corridor::ntcip
