// Raises the calling thread to real-time (SCHED_FIFO) scheduling for a scope and restores its own
// scheduling when the scope ends, so a congestion batch's repairs are not preempted by the
// server's other threads (position reports, the commit queue, a load generator on the same cores).
#pragma once

namespace corridor::server {

class RealtimeScope {
 public:
  // `priority` 0 leaves the thread alone; 1..99 asks for SCHED_FIFO at that priority. Without the
  // right to it (root, CAP_SYS_NICE or RLIMIT_RTPRIO) the thread keeps its scheduling: granted()
  // says which happened.
  explicit RealtimeScope(int priority);
  ~RealtimeScope();
  RealtimeScope(const RealtimeScope&) = delete;
  RealtimeScope& operator=(const RealtimeScope&) = delete;

  [[nodiscard]] bool granted() const { return raised_; }

 private:
  bool raised_ = false;
  int policy_ = 0;
  int priority_ = 0;  // the thread's own, restored on exit
};

// The highest priority RealtimeScope accepts (SCHED_FIFO's maximum, 99 on Linux).
int max_realtime_priority();

}  // namespace corridor::server
