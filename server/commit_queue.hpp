// Group commit: writes from many requests share one SQLite transaction on a single writer thread,
// and each request learns through its ticket when the transaction holding its writes has
// committed. A burst of position reports then costs one WAL append instead of one per report,
// and no request thread waits on the disk while it holds the dispatch state.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "server/store.hpp"

namespace corridor::server {

// The outcome of one submitted write: durable, or failed with a message.
class CommitTicket {
 public:
  using Continuation = std::function<void(const std::string* error)>;

  // A ticket that is already durable, for writes that needed no storage.
  static std::shared_ptr<CommitTicket> done();

  // Blocks until the outcome is known; throws StoreError if the write failed.
  void wait();
  // Calls `then` once with nullptr (durable) or the error, on the writer thread or, if the outcome
  // is already known, at once on the caller's. At most one continuation per ticket.
  void on_done(Continuation then);
  // Called by the queue.
  void complete(std::optional<std::string> error);

 private:
  std::mutex mutex_;
  std::condition_variable cv_;
  bool done_ = false;
  std::optional<std::string> error_;
  Continuation then_;
};

class CommitQueue {
 public:
  using Write = std::function<void(Store&)>;

  // Starts the writer thread. The store must outlive the queue. The writer's nice value is raised by
  // `lower_priority_by` (lower_thread_priority), so that it yields a contended core to repairs.
  explicit CommitQueue(Store& store, std::size_t max_batch = 2048, int lower_priority_by = 0);
  // Commits everything already submitted, then stops.
  ~CommitQueue();
  CommitQueue(const CommitQueue&) = delete;
  CommitQueue& operator=(const CommitQueue&) = delete;

  // Queues a write; it commits with whatever else is queued. Writes commit in submission order.
  std::shared_ptr<CommitTicket> submit(Write write);
  // Submits and waits: for writes that must be durable before the caller changes anything.
  // Throws StoreError when the write failed.
  void run(Write write) { submit(std::move(write))->wait(); }
  // Waits until everything submitted so far is committed or failed.
  void flush();

  struct Stats {
    std::size_t commits = 0;
    std::size_t writes = 0;
    std::size_t largest_batch = 0;
  };
  [[nodiscard]] Stats stats() const;

 private:
  struct Item {
    Write write;
    std::shared_ptr<CommitTicket> ticket;
  };
  void loop();
  // One transaction for the whole batch; if it fails, each write alone, so that one bad write
  // does not fail the others.
  void commit(std::deque<Item>& batch);

  Store& store_;
  std::size_t max_batch_;
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<Item> queue_;
  bool stopping_ = false;
  Stats stats_;
  std::thread writer_;
};

}  // namespace corridor::server
