#include "sim/tripinfo.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "sim/errors.hpp"

namespace corridor::sim {
namespace {

TEST(TripInfo, ReadsTravelTimeLossStopsAndUnfinishedTrips) {
  const auto file = std::filesystem::temp_directory_path() / "corridor_tripinfo_test.xml";
  std::ofstream(file) << R"(<?xml version="1.0"?>
<tripinfos>
  <tripinfo id="bg0" depart="1.00" arrival="91.00" duration="90.00" waitingTime="12.00" waitingCount="2" timeLoss="30.50" vType="DEFAULT_VEHTYPE"/>
  <tripinfo id="ev" depart="300.00" arrival="-1" duration="40.00" waitingTime="0.00" waitingCount="0" timeLoss="3.25" vType="ev"/>
</tripinfos>
)";
  const auto trips = read_tripinfo(file);
  ASSERT_EQ(trips.size(), 2u);
  EXPECT_EQ(trips[0].id, "bg0");
  EXPECT_DOUBLE_EQ(trips[0].duration_s, 90.0);
  EXPECT_DOUBLE_EQ(trips[0].time_loss_s, 30.5);
  EXPECT_EQ(trips[0].waiting_count, 2);
  EXPECT_EQ(trips[1].vtype, "ev");
  EXPECT_LT(trips[1].arrival_s, 0.0);
  std::ofstream(file) << "<tripinfos><tripinfo id=";
  EXPECT_THROW(read_tripinfo(file), SimError);
  std::filesystem::remove(file);
  EXPECT_THROW(read_tripinfo(file), SimError);
}

}  // namespace
}  // namespace corridor::sim
