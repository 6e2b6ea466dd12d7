#include "server/thread_priority.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "server/commit_queue.hpp"
#include "server/dispatch_service.hpp"
#include "server/http_server.hpp"
#include "server/router.hpp"
#include "tests/server/api_fixture.hpp"
#include "tests/server/temp_db.hpp"

namespace corridor::server {
namespace {

int own_nice() { return getpriority(PRIO_PROCESS, static_cast<id_t>(gettid())); }

// The nice value of every thread of this process, read as the kernel reports it (field 19 of
// /proc/self/task/<tid>/stat, after the command's closing parenthesis).
std::vector<int> thread_nices() {
  std::vector<int> out;
  for (const auto& task : std::filesystem::directory_iterator("/proc/self/task")) {
    std::ifstream in(task.path() / "stat");
    std::string stat((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const auto close = stat.rfind(')');
    if (close == std::string::npos) continue;
    std::istringstream fields(stat.substr(close + 2));
    std::string field;
    // Fields 3.. follow the parenthesis; nice is field 19, the 17th of them.
    for (int i = 3; i <= 19 && fields >> field; ++i) {
      if (i == 19) out.push_back(std::stoi(field));
    }
  }
  return out;
}

// Run under `nice` the process may start too close to 19 for a lowering to show.
#define SKIP_ABOVE_NICE(limit)                                                                  \
  if (own_nice() > (limit)) GTEST_SKIP() << "the tests run at nice " << own_nice() << ", above " << (limit)

TEST(LowerThreadPriority, RaisesOnlyTheCallersNiceAndCapsItAt19) {
  SKIP_ABOVE_NICE(15);
  const int main_before = own_nice();
  std::thread worker([&] {
    const int before = own_nice();
    EXPECT_TRUE(lower_thread_priority(0));
    EXPECT_EQ(own_nice(), before);
    EXPECT_TRUE(lower_thread_priority(3));
    EXPECT_EQ(own_nice(), before + 3);
    EXPECT_TRUE(lower_thread_priority(40));
    EXPECT_EQ(own_nice(), 19);
  });
  worker.join();
  EXPECT_EQ(own_nice(), main_before);
}

TEST(LowerThreadPriority, TheCommitWriterRunsBelowItsCreator) {
  TempDb db;
  Store store(db.path());
  SKIP_ABOVE_NICE(15);
  const int creator = own_nice();
  int writer = -100;
  {
    CommitQueue queue(store, 2048, 4);
    // A write runs on the writer thread: it reads that thread's own nice value.
    queue.run([&](Store&) { writer = own_nice(); });
  }
  EXPECT_EQ(writer, creator + 4);
  EXPECT_EQ(own_nice(), creator);
}

TEST(LowerThreadPriority, TheServersIoThreadsRunBelowItsWorkersAndTheCallerKeepsItsOwn) {
  SKIP_ABOVE_NICE(13);
  const int base = own_nice();
  const auto count = [](const std::vector<int>& nices, int value) { return std::count(nices.begin(), nices.end(), value); };
  const auto before = count(thread_nices(), base + 6);
  DispatchService service(testing::api_grid(), {}, nullptr, 0.0);
  Router router(service, testing::api_auth(), {}, [] { return 100.0; });
  ServerLimits limits;
  limits.io_nice = 6;
  HttpServer http(router, service, limits, "127.0.0.1", 0, 3);
  int runner_after = -100;
  std::thread runner([&] {
    http.run();
    runner_after = own_nice();
  });
  // The three I/O threads lower themselves as they start.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (count(thread_nices(), base + 6) < before + 3 && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  EXPECT_EQ(count(thread_nices(), base + 6), before + 3);
  http.stop();
  runner.join();
  EXPECT_EQ(runner_after, base);
}

TEST(LowerThreadPriority, TheServiceHandsItsBackgroundNiceToTheCommitWriter) {
  SKIP_ABOVE_NICE(12);
  const int base = own_nice();
  const auto at = [&] {
    const std::vector<int> nices = thread_nices();
    return std::count(nices.begin(), nices.end(), base + 7);
  };
  const auto before = at();
  TempDb db;
  Store store(db.path());
  DispatchConfig config;
  config.background_nice = 7;
  DispatchService service(testing::api_grid(), config, &store, 0.0);
  service.flush();  // the writer has started, and lowered itself, once it has committed something
  EXPECT_EQ(at(), before + 1);
  DispatchConfig bad;
  bad.background_nice = 20;
  EXPECT_THROW(DispatchService(testing::api_grid(), bad, nullptr, 0.0), std::invalid_argument);
}

TEST(LowerThreadPriority, TheServerRejectsAnIoNiceOutside0To19) {
  DispatchService service(testing::api_grid(), {}, nullptr, 0.0);
  Router router(service, testing::api_auth(), {}, [] { return 100.0; });
  for (const int bad : {-1, 20}) {
    ServerLimits limits;
    limits.io_nice = bad;
    EXPECT_THROW(HttpServer(router, service, limits, "127.0.0.1", 0, 1), std::invalid_argument);
  }
}

}  // namespace
}  // namespace corridor::server
