// A progress bar on stderr for long imports; silent for work that finishes within about a second.
#pragma once

#include <chrono>
#include <cstdint>
#include <string>

namespace corridor::maps {

class ProgressBar {
 public:
  ProgressBar(std::string label, std::uint64_t total);
  ~ProgressBar();
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;

  void update(std::uint64_t done);
  void finish();

 private:
  std::string label_;
  std::uint64_t total_;
  std::chrono::steady_clock::time_point start_;
  int last_percent_ = -1;
  bool shown_ = false;
  bool finished_ = false;
  bool tty_ = false;
};

}  // namespace corridor::maps
