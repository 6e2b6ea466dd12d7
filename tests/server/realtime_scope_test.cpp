#include "server/realtime_scope.hpp"

#include <pthread.h>
#include <sched.h>

#include <gtest/gtest.h>

#include <thread>

namespace corridor::server {
namespace {

struct Scheduling {
  int policy = -1;
  int priority = -1;
};

Scheduling current() {
  Scheduling s;
  sched_param p{};
  EXPECT_EQ(pthread_getschedparam(pthread_self(), &s.policy, &p), 0);
  s.priority = p.sched_priority;
  return s;
}

TEST(RealtimeScope, ZeroLeavesTheThreadAlone) {
  const Scheduling before = current();
  {
    const RealtimeScope scope(0);
    EXPECT_FALSE(scope.granted());
    EXPECT_EQ(current().policy, before.policy);
  }
  EXPECT_EQ(current().policy, before.policy);
}

// Whether the machine grants SCHED_FIFO is its own business (root, CAP_SYS_NICE, RLIMIT_RTPRIO, or
// none); either way the thread runs as granted() says inside, and as before once the scope ends.
TEST(RealtimeScope, RaisesWhereGrantedAndAlwaysRestores) {
  std::thread worker([] {
    const Scheduling before = current();
    ASSERT_NE(before.policy, SCHED_FIFO);
    {
      const RealtimeScope scope(3);
      const Scheduling inside = current();
      if (scope.granted()) {
        EXPECT_EQ(inside.policy, SCHED_FIFO);
        EXPECT_EQ(inside.priority, 3);
      } else {
        EXPECT_EQ(inside.policy, before.policy);
      }
    }
    const Scheduling after = current();
    EXPECT_EQ(after.policy, before.policy);
    EXPECT_EQ(after.priority, before.priority);
  });
  worker.join();
}

TEST(RealtimeScope, MaximumIsSchedFifos) { EXPECT_EQ(max_realtime_priority(), sched_get_priority_max(SCHED_FIFO)); }

}  // namespace
}  // namespace corridor::server
