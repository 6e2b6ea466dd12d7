#include "server/commit_queue.hpp"

#include <gtest/gtest.h>
#include <sqlite3.h>

#include <future>

#include "tests/server/temp_db.hpp"

namespace corridor::server {
namespace {

PositionReport report(const std::string& vehicle, double timestamp_s) {
  PositionReport p;
  p.vehicle_id = vehicle;
  p.position = {43.73, 7.42};
  p.timestamp_s = timestamp_s;
  p.source = "gps";
  return p;
}

CommitQueue::Write insert(const std::string& vehicle, double timestamp_s) {
  return [p = report(vehicle, timestamp_s)](Store& s) { s.insert_position(p, std::nullopt, p.timestamp_s); };
}

// Holds the writer thread inside a write until release(), so that what is submitted meanwhile
// queues up behind it.
class HeldWriter {
 public:
  explicit HeldWriter(CommitQueue& queue) {
    queue.submit([this, gate = release_.get_future().share()](Store&) {
      busy_.set_value();
      gate.wait();
    });
    busy_.get_future().wait();
  }
  void release() { release_.set_value(); }

 private:
  std::promise<void> release_;
  std::promise<void> busy_;
};

TEST(CommitQueue, WritesCommitInSubmissionOrder) {
  TempDb db;
  Store store(db.path());
  {
    CommitQueue queue(store);
    for (int i = 0; i < 500; ++i) queue.submit(insert("amb-1", i));
    queue.flush();
    EXPECT_EQ(store.count("positions"), 500u);
    EXPECT_EQ(store.last_position("amb-1")->timestamp_s, 499.0);
  }
}

TEST(CommitQueue, WritesQueuedDuringACommitShareTheNextTransaction) {
  TempDb db;
  Store store(db.path());
  CommitQueue queue(store);
  // The first write holds the writer while 300 more arrive; they must commit together.
  HeldWriter held(queue);
  std::vector<std::shared_ptr<CommitTicket>> tickets;
  for (int i = 0; i < 300; ++i) tickets.push_back(queue.submit(insert("amb-1", i)));
  held.release();
  for (const auto& t : tickets) t->wait();
  const auto stats = queue.stats();
  EXPECT_EQ(stats.writes, 301u);
  EXPECT_EQ(stats.commits, 2u);
  EXPECT_EQ(stats.largest_batch, 300u);
  EXPECT_EQ(store.count("positions"), 300u);
}

TEST(CommitQueue, AFailingWriteFailsOnlyItsOwnTicket) {
  TempDb db;
  Store store(db.path());
  CommitQueue queue(store);
  HeldWriter held(queue);  // so that all three share one batch
  auto before = queue.submit(insert("amb-1", 1.0));
  auto bad = queue.submit([](Store&) { throw StoreError("disk full"); });
  auto after = queue.submit(insert("amb-1", 2.0));
  held.release();
  EXPECT_NO_THROW(before->wait());
  EXPECT_THROW(bad->wait(), StoreError);
  EXPECT_NO_THROW(after->wait());
  EXPECT_EQ(store.count("positions"), 2u);
}

TEST(CommitQueue, DestructionCommitsWhatIsQueued) {
  TempDb db;
  Store store(db.path());
  {
    CommitQueue queue(store);
    for (int i = 0; i < 50; ++i) queue.submit(insert("amb-1", i));
  }
  EXPECT_EQ(store.count("positions"), 50u);
}

TEST(CommitTicket, ContinuationRunsOnceWithTheOutcomeWhetherSetBeforeOrAfter) {
  auto pending = std::make_shared<CommitTicket>();
  int calls = 0;
  std::string seen;
  pending->on_done([&](const std::string* error) {
    ++calls;
    seen = error != nullptr ? *error : "ok";
  });
  EXPECT_EQ(calls, 0);
  pending->complete("disk full");
  EXPECT_EQ(calls, 1);
  EXPECT_EQ(seen, "disk full");

  int late_calls = 0;
  CommitTicket::done()->on_done([&](const std::string* error) {
    ++late_calls;
    EXPECT_EQ(error, nullptr);
  });
  EXPECT_EQ(late_calls, 1);
}

TEST(Store, ASecondServerCannotOpenADatabaseInUse) {
  TempDb db;
  {
    Store first(db.path());
    try {
      Store second(db.path());
      FAIL() << "a second store opened a database in use";
    } catch (const StoreError& e) {
      EXPECT_NE(std::string(e.what()).find("in use by another corridor server"), std::string::npos) << e.what();
    }
  }
  EXPECT_NO_THROW(Store again(db.path()));  // released with the first
}

TEST(Store, CheckpointsKeepTheWalBoundedUnderSustainedWrites) {
  TempDb db;
  Store store(db.path());
  CommitQueue queue(store);
  // 8,000 commits of two pages or more each: without checkpoints the WAL would pass 80 MB. The
  // writer rewinds it past about 16 MB, once the PASSIVE checkpoint running then is done; on a
  // busy machine that one may take a while, hence the margin.
  for (int i = 0; i < 8000; ++i) queue.submit(insert("amb-" + std::to_string(i % 50), i))->wait();
  EXPECT_EQ(store.count("positions"), 8000u);
  const auto wal = std::filesystem::file_size(db.path().string() + "-wal");
  EXPECT_LT(wal, 32u << 20) << "WAL of " << wal << " bytes";
  EXPECT_GT(std::filesystem::file_size(db.path()), 100u << 10) << "checkpoints should have moved pages into the database";
}

}  // namespace
}  // namespace corridor::server
