// Child processes for SUMO and its tools: spawned with their output in a log file, waited for,
// and killed if their owner goes away first.
#pragma once

#include <sys/types.h>

#include <filesystem>
#include <string>
#include <vector>

namespace corridor::sim {

class ChildProcess {
 public:
  // Starts argv[0] (searched on PATH) with stdout and stderr appended to `log_file`. SUMO_HOME is
  // set to /usr/share/sumo for the child unless the environment already sets it.
  ChildProcess(const std::vector<std::string>& argv, const std::filesystem::path& log_file);
  ~ChildProcess();
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  // Blocks until the child ends; its exit status (128 + signal when killed).
  int wait();
  [[nodiscard]] bool running();
  void kill();
  [[nodiscard]] pid_t pid() const { return pid_; }

 private:
  pid_t pid_ = -1;
  int status_ = -1;
};

// Runs a tool to completion. Throws SimError with the command and the end of its log on failure.
void run_tool(const std::vector<std::string>& argv, const std::filesystem::path& log_file);

// A TCP port that was free a moment ago on the loopback interface.
int free_tcp_port();

// True once `child` listens on `port` (read from /proc, without connecting: SUMO takes the first
// connection as its client). False if it ends first, or `timeout_s` passes.
bool wait_until_listening(int port, ChildProcess& child, double timeout_s);

// The last `lines` lines of a text file, for error messages.
std::string tail_of(const std::filesystem::path& file, int lines = 15);

}  // namespace corridor::sim
