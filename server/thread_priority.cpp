#include "server/thread_priority.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <cerrno>

namespace corridor::server {

bool lower_thread_priority(int steps) noexcept {
  if (steps <= 0) return true;
  // PRIO_PROCESS with a thread id names that one thread on Linux, not the whole process.
  const auto self = static_cast<id_t>(gettid());
  errno = 0;
  const int now = getpriority(PRIO_PROCESS, self);
  if (now == -1 && errno != 0) return false;
  return setpriority(PRIO_PROCESS, self, steps >= 19 - now ? 19 : now + steps) == 0;
}

}  // namespace corridor::server
