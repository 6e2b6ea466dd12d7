// A database path in the temp directory, unique per process and test, removed with its WAL,
// shared-memory and lock files.
#pragma once

#include <unistd.h>

#include <filesystem>
#include <string>

namespace corridor::server {

class TempDb {
 public:
  TempDb() : path_(std::filesystem::temp_directory_path() / ("corridor-db-" + std::to_string(::getpid()) + "-" +
                                                             std::to_string(counter_++) + ".db")) {
    remove_files();  // a killed run with the same pid may have left its database behind
  }
  ~TempDb() { remove_files(); }
  TempDb(const TempDb&) = delete;
  TempDb& operator=(const TempDb&) = delete;
  [[nodiscard]] const std::filesystem::path& path() const { return path_; }

 private:
  void remove_files() const {
    for (const char* suffix : {"", "-wal", "-shm", ".lock"}) std::filesystem::remove(path_.string() + suffix);
  }

  static inline int counter_ = 0;
  std::filesystem::path path_;
};

}  // namespace corridor::server
