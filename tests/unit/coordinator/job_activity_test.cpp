// The dashboard's view of a job from the coordinator's side
// (coordinator/job_activity.h, coordinator/job_log.h).
#include "coordinator/job_activity.h"

#include <gtest/gtest.h>
#include <spdlog/logger.h>

#include <memory>
#include <numeric>

#include "coordinator/job_log.h"

namespace portico {
namespace {

LinearImage ramp(uint32_t width, uint32_t height) {
  LinearImage image;
  image.width = width, image.height = height;
  image.rgb.resize(size_t(width) * height * 3);
  for (size_t i = 0; i < image.rgb.size(); ++i) image.rgb[i] = float(i % 97) / 8.0f;
  return image;
}

TEST(ShrinkImage, AveragesWholeBlocksDownToTheLongestSideAsked) {
  const LinearImage film = ramp(1000, 500);
  const LinearImage small = shrinkImage(film, 300);
  // Factor 4 (3 would give 334 pixels): 250 x 125.
  EXPECT_EQ(small.width, 250u);
  EXPECT_EQ(small.height, 125u);
  float expected = 0;
  for (uint32_t y = 0; y < 4; ++y)
    for (uint32_t x = 0; x < 4; ++x) expected += film.rgb[(size_t(y) * film.width + x) * 3 + 1];
  EXPECT_FLOAT_EQ(small.rgb[1], expected / 16);
}

TEST(ShrinkImage, KeepsASmallFilmAndCapsWhatIsAsked) {
  const LinearImage film = ramp(30, 20);
  EXPECT_EQ(shrinkImage(film, 640).rgb, film.rgb);
  const LinearImage huge = ramp(4096, 100);
  EXPECT_EQ(shrinkImage(huge, 0).width, kMaxPreviewSide);
  EXPECT_EQ(shrinkImage(huge, 100000).width, kMaxPreviewSide);
  // Edge blocks are partial: their mean is over the pixels they have.
  const LinearImage odd = ramp(5, 1);
  const LinearImage two = shrinkImage(odd, 3);
  ASSERT_EQ(two.width, 3u);
  EXPECT_FLOAT_EQ(two.rgb[6], odd.rgb[12]);
}

TEST(JobLog, KeepsTheLinesNamingEachJobBoundedAndOldestJobsGoFirst) {
  auto sink = std::make_shared<JobLog>();
  spdlog::logger logger("job-log-test", sink);
  logger.info("job 3 submitted: 400000 photons");
  logger.info("lease 12 (job 3 cell 4, attempt 2) requeued: worker w1 left");
  logger.info("worker w2 joined (1 cores, 1024 MiB budget)");   // no job: kept nowhere
  logger.warn("job 4 reuses the photon pass of job 3");
  logger.info("job 30 submitted");   // "job 3" is not a prefix of it
  const auto three = sink->lines(3);
  ASSERT_EQ(three.size(), 3u);
  EXPECT_NE(three[0].find("job 3 submitted"), std::string::npos);
  EXPECT_NE(three[1].find("requeued"), std::string::npos);
  EXPECT_NE(three[2].find("[warning] job 4 reuses"), std::string::npos);
  EXPECT_EQ(sink->lines(4).size(), 1u);
  EXPECT_EQ(sink->lines(30).size(), 1u);
  EXPECT_TRUE(sink->lines(5).empty());
  for (size_t i = 0; i < JobLog::kLinesPerJob + 5; ++i) logger.info("job 4 line {}", i);
  const auto four = sink->lines(4);
  ASSERT_EQ(four.size(), JobLog::kLinesPerJob);
  EXPECT_NE(four.back().find(fmt::format("line {}", JobLog::kLinesPerJob + 4)), std::string::npos);
  for (uint64_t job = 100; job < 100 + JobLog::kJobs; ++job) logger.info("job {} submitted", job);
  EXPECT_TRUE(sink->lines(3).empty());
  EXPECT_EQ(sink->lines(100 + JobLog::kJobs - 1).size(), 1u);
}

}  // namespace
}  // namespace portico
