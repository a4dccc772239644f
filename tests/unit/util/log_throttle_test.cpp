#include "common/util/log_throttle.h"

#include <gtest/gtest.h>

namespace portico {
namespace {

TEST(LogThrottle, LogsTheFirstTimeThenCountsWhatItLeavesOut) {
  LogThrottle hourly(std::chrono::hours(1));
  EXPECT_EQ(hourly.admit("key A"), std::optional<uint64_t>(0));
  EXPECT_EQ(hourly.admit("key A"), std::nullopt);
  EXPECT_EQ(hourly.admit("key A"), std::nullopt);
  EXPECT_EQ(hourly.admit("key B"), std::optional<uint64_t>(0));   // keys are independent

  LogThrottle always(std::chrono::milliseconds(0));
  EXPECT_EQ(always.admit("k"), std::optional<uint64_t>(0));
  EXPECT_EQ(always.admit("k"), std::optional<uint64_t>(0));
  EXPECT_EQ(leftOutSuffix(0), "");
  EXPECT_EQ(leftOutSuffix(2), "; 2 more since the last line");
}

}  // namespace
}  // namespace portico
