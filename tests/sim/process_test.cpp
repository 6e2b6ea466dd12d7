#include "sim/process.hpp"

#include <gtest/gtest.h>

#include <fstream>

#include "sim/errors.hpp"

namespace corridor::sim {
namespace {

std::filesystem::path temp(const char* name) { return std::filesystem::temp_directory_path() / name; }

TEST(ChildProcess, ReportsTheExitStatusAndKillsWhatIsStillRunningOnDestruction) {
  const auto log = temp("corridor_process_test.log");
  std::filesystem::remove(log);
  ChildProcess quick({"/bin/sh", "-c", "echo hello; exit 3"}, log);
  EXPECT_EQ(quick.wait(), 3);
  EXPECT_FALSE(quick.running());
  EXPECT_NE(tail_of(log).find("hello"), std::string::npos);
  pid_t pid = 0;
  {
    ChildProcess slow({"/bin/sleep", "30"}, log);
    pid = slow.pid();
    EXPECT_TRUE(slow.running());
  }
  EXPECT_FALSE(std::filesystem::exists("/proc/" + std::to_string(pid) + "/status")) << "child left running";
  std::filesystem::remove(log);
}

TEST(ChildProcess, MissingProgramOrFailingToolGivesAnErrorThatNamesIt) {
  const auto log = temp("corridor_process_test2.log");
  EXPECT_THROW(ChildProcess({"corridor-no-such-program"}, log), SimError);
  try {
    run_tool({"/bin/sh", "-c", "echo broken input >&2; exit 1"}, log);
    ADD_FAILURE() << "a failing tool passed";
  } catch (const SimError& e) {
    EXPECT_NE(std::string(e.what()).find("exit status 1"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("broken input"), std::string::npos) << e.what();
  }
  std::filesystem::remove(log);
}

TEST(ChildProcess, WaitUntilListeningSeesOnlyTheChildsOwnSocket) {
  const auto log = temp("corridor_process_test3.log");
  const int port = free_tcp_port();
  EXPECT_GT(port, 0);
  // A child that never listens, then ends: false, and quickly.
  ChildProcess idle({"/bin/sleep", "0.2"}, log);
  EXPECT_FALSE(wait_until_listening(port, idle, 10.0));
  // A child that listens on the port.
  ChildProcess server({"/usr/bin/python3", "-c",
                       "import socket,time; s=socket.socket(); s.bind(('127.0.0.1'," + std::to_string(port) +
                           ")); s.listen(); time.sleep(30)"},
                      log);
  EXPECT_TRUE(wait_until_listening(port, server, 20.0));
  // Another process does not own that socket.
  ChildProcess other({"/bin/sleep", "30"}, log);
  EXPECT_FALSE(wait_until_listening(port, other, 0.2));
  std::filesystem::remove(log);
}

}  // namespace
}  // namespace corridor::sim
