#include "maps/progress.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdio>

namespace corridor::maps {

ProgressBar::ProgressBar(std::string label, std::uint64_t total)
    : label_(std::move(label)), total_(total == 0 ? 1 : total), start_(std::chrono::steady_clock::now()),
      tty_(::isatty(STDERR_FILENO) == 1) {}

ProgressBar::~ProgressBar() { finish(); }

void ProgressBar::update(std::uint64_t done) {
  if (finished_) return;
  const auto elapsed = std::chrono::steady_clock::now() - start_;
  if (!shown_ && elapsed < std::chrono::seconds(1)) return;
  const int percent = static_cast<int>(100 * std::min(done, total_) / total_);
  // On a terminal redraw in place; in logs, one line per 10 % is enough.
  if (percent == last_percent_ || (!tty_ && percent / 10 == last_percent_ / 10)) return;
  last_percent_ = percent;
  shown_ = true;
  constexpr int kWidth = 30;
  const int filled = percent * kWidth / 100;
  std::fprintf(stderr, "%s%s [%.*s%*s] %3d%%%s", tty_ ? "\r" : "", label_.c_str(), filled,
               "##############################", kWidth - filled, "", percent, tty_ ? "" : "\n");
  std::fflush(stderr);
}

void ProgressBar::finish() {
  if (finished_) return;
  if (shown_) update(total_);
  finished_ = true;
  if (shown_ && tty_) std::fputc('\n', stderr);
}

}  // namespace corridor::maps
