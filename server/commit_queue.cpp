#include "server/commit_queue.hpp"

#include "server/thread_priority.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>

namespace corridor::server {

std::shared_ptr<CommitTicket> CommitTicket::done() {
  auto t = std::make_shared<CommitTicket>();
  t->complete(std::nullopt);
  return t;
}

void CommitTicket::wait() {
  std::unique_lock lock(mutex_);
  cv_.wait(lock, [&] { return done_; });
  if (error_) throw StoreError(*error_);
}

void CommitTicket::on_done(Continuation then) {
  {
    std::lock_guard lock(mutex_);
    if (!done_) {
      then_ = std::move(then);
      return;
    }
  }
  then(error_ ? &*error_ : nullptr);
}

void CommitTicket::complete(std::optional<std::string> error) {
  Continuation then;
  {
    std::lock_guard lock(mutex_);
    done_ = true;
    error_ = std::move(error);
    then = std::move(then_);
  }
  cv_.notify_all();
  // Outside the lock: the continuation may be slow or look at this ticket again.
  if (then) then(error_ ? &*error_ : nullptr);
}

CommitQueue::CommitQueue(Store& store, std::size_t max_batch, int lower_priority_by)
    : store_(store), max_batch_(std::max<std::size_t>(1, max_batch)), writer_([this, lower_priority_by] {
        if (!lower_thread_priority(lower_priority_by)) {
          spdlog::warn("event=writer_nice_denied nice_steps={} hint=\"the commit writer runs at the process's priority\"",
                       lower_priority_by);
        }
        loop();
      }) {}

CommitQueue::~CommitQueue() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  cv_.notify_all();
  writer_.join();
}

std::shared_ptr<CommitTicket> CommitQueue::submit(Write write) {
  auto ticket = std::make_shared<CommitTicket>();
  {
    std::lock_guard lock(mutex_);
    queue_.push_back({std::move(write), ticket});
  }
  cv_.notify_one();
  return ticket;
}

void CommitQueue::flush() { submit([](Store&) {})->wait(); }

CommitQueue::Stats CommitQueue::stats() const {
  std::lock_guard lock(mutex_);
  return stats_;
}

void CommitQueue::loop() {
  for (;;) {
    std::deque<Item> batch;
    {
      std::unique_lock lock(mutex_);
      cv_.wait(lock, [&] { return stopping_ || !queue_.empty(); });
      if (queue_.empty()) return;  // stopping, and everything is committed
      const std::size_t n = std::min(queue_.size(), max_batch_);
      batch.insert(batch.end(), std::make_move_iterator(queue_.begin()),
                   std::make_move_iterator(queue_.begin() + static_cast<std::ptrdiff_t>(n)));
      queue_.erase(queue_.begin(), queue_.begin() + static_cast<std::ptrdiff_t>(n));
    }
    commit(batch);
  }
}

void CommitQueue::commit(std::deque<Item>& batch) {
  std::optional<std::string> error;
  try {
    Store::Transaction tx(store_);
    for (Item& item : batch) item.write(store_);
    tx.commit();
  } catch (const std::exception& e) {
    error = e.what();
  } catch (...) {
    error = "unknown error";
  }
  if (!error) {
    {
      std::lock_guard lock(mutex_);
      ++stats_.commits;
      stats_.writes += batch.size();
      stats_.largest_batch = std::max(stats_.largest_batch, batch.size());
    }
    for (Item& item : batch) item.ticket->complete(std::nullopt);
    return;
  }
  if (batch.size() == 1) {
    spdlog::error("event=write_failed error=\"{}\"", *error);
    batch.front().ticket->complete(error);
    return;
  }
  spdlog::warn("event=batch_write_failed writes={} error=\"{}\" action=retry_one_by_one", batch.size(), *error);
  for (Item& item : batch) {
    std::deque<Item> one;
    one.push_back(std::move(item));
    commit(one);
  }
}

}  // namespace corridor::server
