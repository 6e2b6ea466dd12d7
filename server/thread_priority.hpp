// Lowers the calling thread's CPU weight, so that where the cores are contended the scheduler
// serves the threads that repair routes first, without any privilege.
#pragma once

namespace corridor::server {

// Adds `steps` to the calling thread's nice value (per thread on Linux), capped at 19; 0 leaves it
// alone. Lowering one's own priority needs no privilege, and it cannot be taken back without one,
// so only threads that keep one role for their whole life call this. Returns whether it took.
bool lower_thread_priority(int steps) noexcept;

}  // namespace corridor::server
