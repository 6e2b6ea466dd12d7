#include "server/realtime_scope.hpp"

#include <pthread.h>
#include <sched.h>

namespace corridor::server {

RealtimeScope::RealtimeScope(int priority) {
  if (priority <= 0) return;
  sched_param own{};
  if (pthread_getschedparam(pthread_self(), &policy_, &own) != 0) return;
  priority_ = own.sched_priority;
  sched_param raised{};
  raised.sched_priority = priority;
  raised_ = pthread_setschedparam(pthread_self(), SCHED_FIFO, &raised) == 0;
}

RealtimeScope::~RealtimeScope() {
  if (!raised_) return;
  sched_param own{};
  own.sched_priority = priority_;
  pthread_setschedparam(pthread_self(), policy_, &own);
}

int max_realtime_priority() { return sched_get_priority_max(SCHED_FIFO); }

}  // namespace corridor::server
