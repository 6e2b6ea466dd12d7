// A fresh directory in the temp directory, unique per process and per instance, removed with its
// contents: the one temporary directory of every test suite.
#pragma once

#include <unistd.h>

#include <filesystem>
#include <string>

namespace corridor::testing {

class TempDir {
 public:
  explicit TempDir(const std::string& prefix = "corridor-test")
      : path_(std::filesystem::temp_directory_path() /
              (prefix + "-" + std::to_string(::getpid()) + "-" + std::to_string(counter()++))) {
    std::filesystem::remove_all(path_);  // a killed run with the same pid may have left it behind
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  [[nodiscard]] const std::filesystem::path& path() const { return path_; }

 private:
  static int& counter() {
    static int c = 0;
    return c;
  }
  std::filesystem::path path_;
};

}  // namespace corridor::testing
