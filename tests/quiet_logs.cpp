// Keeps test output readable: decisions are logged at info level in production, warnings only here.
#include <gtest/gtest.h>
#include <spdlog/spdlog.h>

namespace {
class QuietLogs : public ::testing::Environment {
 public:
  void SetUp() override { spdlog::set_level(spdlog::level::warn); }
};
[[maybe_unused]] auto* const kQuietLogs = ::testing::AddGlobalTestEnvironment(new QuietLogs);
}  // namespace
