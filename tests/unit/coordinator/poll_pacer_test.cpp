#include <gtest/gtest.h>

#include <chrono>

#include "coordinator/cli/progress.h"

namespace portico::cli {
namespace {

using std::chrono::milliseconds;

nlohmann::json renderStatus(int64_t cameraRaysDone, int64_t cameraRaysTotal) {
  return {{"state", "rendering"},
          {"progress", {{"camera_rays_done", cameraRaysDone}, {"camera_rays_total", cameraRaysTotal}}}};
}

TEST(PollPacer, WaitsTheUsualIntervalUntilThePaceIsKnown) {
  const auto start = PollPacer::Clock::time_point{} + std::chrono::hours(1);
  PollPacer pacer(start);
  EXPECT_EQ(pacer.next(renderStatus(0, 1000), start + milliseconds(3000)), milliseconds(300));
  EXPECT_EQ(pacer.next(renderStatus(100, 1000), start + milliseconds(3100)), milliseconds(310));   // first rays seen
  EXPECT_EQ(pacer.next(nlohmann::json{{"state", "rendering"}}, start + milliseconds(3200)), milliseconds(320));
}

TEST(PollPacer, WaitsUntilThePredictedEndAtLeastAQuarterOfTheInterval) {
  const auto start = PollPacer::Clock::time_point{} + std::chrono::hours(1);
  PollPacer pacer(start);
  pacer.next(renderStatus(100, 1000), start + milliseconds(2000));
  // 800 rays in 2 s: the last 100 take 250 ms, under the 400 ms interval.
  EXPECT_EQ(pacer.next(renderStatus(900, 1000), start + milliseconds(4000)), milliseconds(250));
  // 890 rays in 2.1 s: the last 10 take ~24 ms; a quarter of 410 ms is the floor.
  EXPECT_EQ(pacer.next(renderStatus(990, 1000), start + milliseconds(4100)), milliseconds(102));
  // Far from the end: the usual interval.
  EXPECT_EQ(pacer.next(renderStatus(200, 100000), start + milliseconds(5000)), milliseconds(500));
}

}  // namespace
}  // namespace portico::cli
