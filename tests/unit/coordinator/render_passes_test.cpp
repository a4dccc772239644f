#include "coordinator/render_passes.h"

#include <capnp/message.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <random>

#include "common/net/message.h"
#include "coordinator/pass_error.h"
#include "tests/support/temp_directory.h"

namespace portico {
namespace {

// A film of `width` x `height` whose pixel p in pass k is value(k, p) on every channel.
template <class Value>
std::vector<FixedRgb> filmOfPasses(uint32_t width, uint32_t height, uint32_t passes, Value value) {
  std::vector<FixedRgb> film(size_t(width) * height);
  for (uint32_t k = 0; k < passes; ++k)
    for (size_t p = 0; p < film.size(); ++p) {
      const int64_t fixed = toFixed(value(k, p));
      film[p] += FixedRgb{fixed, fixed, fixed};
    }
  return film;
}

// The estimate as the definition says it, from each pass's own image.
double directEstimate(uint32_t width, uint32_t height, uint32_t passes, const std::vector<std::vector<double>>& images) {
  const uint32_t across = width / 16, down = height / 16;
  double total = 0;
  for (const auto& image : images)
    for (double v : image) total += v;
  const double imageMean = total / (double(passes) * width * height);
  double squares = 0;
  int used = 0;
  for (uint32_t by = 0; by < down; ++by)
    for (uint32_t bx = 0; bx < across; ++bx) {
      std::vector<double> means;
      for (const auto& image : images) {
        double sum = 0;
        for (uint32_t y = by * 16; y < by * 16 + 16; ++y)
          for (uint32_t x = bx * 16; x < bx * 16 + 16; ++x) sum += image[size_t(y) * width + x];
        means.push_back(sum / 256);
      }
      double mean = 0;
      for (double m : means) mean += m / passes;
      if (!(mean > 0.05 * imageMean)) continue;
      double variance = 0;
      for (double m : means) variance += (m - mean) * (m - mean) / (passes - 1);
      const double relative = std::sqrt(variance / passes) / mean;
      squares += relative * relative;
      ++used;
    }
  return std::sqrt(squares / used);
}

TEST(PassError, MatchesTheDefinitionPassByPass) {
  const uint32_t width = 40, height = 36;   // 2 x 2 whole blocks, and partial ones at the edges
  std::mt19937 random(5);
  std::uniform_real_distribution<float> noise(0.5f, 1.5f);
  std::vector<std::vector<double>> images;
  PassBlockStatistics statistics;
  for (uint32_t pass = 1; pass <= 5; ++pass) {
    std::vector<double> image(size_t(width) * height);
    for (size_t p = 0; p < image.size(); ++p) image[p] = fromFixed(toFixed(noise(random) * (p % 7 + 1)));
    images.push_back(image);
    const auto film = filmOfPasses(width, height, pass, [&](uint32_t k, size_t p) { return float(images[k][p]); });
    const PassError error = addPassAndEstimate(film, width, height, pass, statistics);
    if (pass == 1) {
      EXPECT_FALSE(error.estimate.has_value());   // one pass has no spread
      continue;
    }
    ASSERT_TRUE(error.estimate.has_value());
    EXPECT_EQ(error.blocksUsed, 4);
    EXPECT_NEAR(*error.estimate, directEstimate(width, height, pass, images), 1e-9) << "pass " << pass;
  }
}

TEST(PassError, IdenticalPassesHaveNoErrorAndDimBlocksAreLeftOut) {
  const uint32_t width = 32, height = 16;   // two blocks: one lit, one at 1 % of it
  const auto value = [](uint32_t, size_t p) { return (p % 32) < 16 ? 1.0f : 0.01f; };
  PassBlockStatistics statistics;
  addPassAndEstimate(filmOfPasses(width, height, 1, value), width, height, 1, statistics);
  const PassError error = addPassAndEstimate(filmOfPasses(width, height, 2, value), width, height, 2, statistics);
  ASSERT_TRUE(error.estimate.has_value());
  EXPECT_EQ(*error.estimate, 0.0);
  EXPECT_EQ(error.blocksUsed, 1);
  // A black image has no block to judge: no estimate.
  PassBlockStatistics black;
  const auto zero = [](uint32_t, size_t) { return 0.0f; };
  addPassAndEstimate(filmOfPasses(width, height, 1, zero), width, height, 1, black);
  EXPECT_FALSE(addPassAndEstimate(filmOfPasses(width, height, 2, zero), width, height, 2, black).estimate);
}

TEST(RenderPasses, TheFirstPassKeepsTheJobsSeedAndTheOthersGetTheirOwn) {
  EXPECT_EQ(passSeed(1, 0), 1u);
  EXPECT_EQ(passSeed(77, 0), 77u);
  EXPECT_NE(passSeed(1, 1), 1u);
  EXPECT_NE(passSeed(1, 1), passSeed(1, 2));
  EXPECT_NE(passSeed(1, 1), passSeed(2, 1));
  EXPECT_EQ(passSeed(9, 3), passSeed(9, 3));
}

struct Spec {
  capnp::MallocMessageBuilder message;
  wire::JobSpec::Builder spec = message.initRoot<wire::JobSpec>();
  Spec(std::optional<double> target, std::optional<double> seconds, uint32_t maxPasses) {
    if (target) spec.getTargetError().setValue(*target);
    if (seconds) spec.getTimeLimit().setSeconds(*seconds);
    spec.setMaxPasses(maxPasses);
  }
};

TEST(RenderPasses, StopAtTheTargetBeforeAPassPastTheTimeLimitOrAtTheMostPasses) {
  Spec target(0.02, std::nullopt, 64);
  EXPECT_EQ(stopAfterPass(target.spec, std::nullopt, {100}), PassStop::None);
  EXPECT_EQ(stopAfterPass(target.spec, 0.03, {100, 200}), PassStop::None);
  EXPECT_EQ(stopAfterPass(target.spec, 0.02, {100, 200}), PassStop::TargetMet);
  std::vector<int64_t> ends;
  for (int i = 1; i <= 64; ++i) ends.push_back(i * 100);
  EXPECT_EQ(stopAfterPass(target.spec, 0.03, ends), PassStop::MaxPasses);

  Spec limit(std::nullopt, 1.0, 64);
  EXPECT_EQ(stopAfterPass(limit.spec, std::nullopt, {400}), PassStop::None);   // 400 + 400 <= 1000
  EXPECT_EQ(stopAfterPass(limit.spec, std::nullopt, {600}), PassStop::TimeLimit);
  // Later passes predict from the passes after the first (which built the photon maps).
  EXPECT_EQ(stopAfterPass(limit.spec, std::nullopt, {500, 600, 700, 800, 900}), PassStop::None);
  EXPECT_EQ(stopAfterPass(limit.spec, std::nullopt, {500, 600, 700, 800, 950}), PassStop::TimeLimit);

  Spec one(std::nullopt, std::nullopt, 1);
  EXPECT_EQ(stopAfterPass(one.spec, std::nullopt, {100}), PassStop::MaxPasses);
  Spec three(std::nullopt, std::nullopt, 3);
  EXPECT_EQ(stopAfterPass(three.spec, 0.0, {100, 200}), PassStop::None);   // no target: exactly three
  EXPECT_EQ(stopAfterPass(three.spec, 0.0, {100, 200, 300}), PassStop::MaxPasses);
}

// Each pass's end, estimate and the block statistics are in jobs.db: a
// store opened again (a restarted coordinator) goes on where it was.
TEST(RenderPasses, PassesAndTheirBlockStatisticsSurviveReopeningJobsDb) {
  const std::filesystem::path path = testing_support::tempPath("render-passes") / "jobs.db";
  Spec spec(1e-9, std::nullopt, 3);
  spec.spec.setWidth(16);
  spec.spec.setHeight(16);
  const std::string packed = net::packToString(spec.message);
  const auto addPass = [](JobStore& store, uint64_t job, float value) {
    std::unordered_map<uint32_t, FixedRgb> sums;
    for (uint32_t p = 0; p < 256; ++p) sums[p] = toFixed(Vec3(value + 0.01f * float(p % 3)));
    store.addFilm(job, sums, 256);
  };
  uint64_t job;
  {
    JobStore store(path.string());
    job = store.createJob(packed, 1000);
    store.setJobState(job, JobState::Render, 2000);
    addPass(store, job, 1.0f);
    const PassEnd first = endRenderPass(store, *store.job(job), spec.spec.asReader(), 2500);
    EXPECT_EQ(first.pass, 1u);
    EXPECT_EQ(first.stop, PassStop::None);
    EXPECT_FALSE(first.errorEstimate);
    addPass(store, job, 1.2f);
  }
  JobStore store(path.string());
  EXPECT_EQ(loadRenderProgress(store.database(), job).passesStarted, 2u);
  const PassEnd second = endRenderPass(store, *store.job(job), spec.spec.asReader(), 3000);
  EXPECT_EQ(second.pass, 2u);
  ASSERT_TRUE(second.errorEstimate);
  // Block means 1.01 and 1.21 (R = G = B): standard deviation 0.1414, / sqrt(2) / 1.11.
  EXPECT_NEAR(*second.errorEstimate, 0.1 / 1.11, 1e-5);
  addPass(store, job, 1.1f);
  const PassEnd third = endRenderPass(store, *store.job(job), spec.spec.asReader(), 3500);
  EXPECT_EQ(third.stop, PassStop::MaxPasses);
  const RenderProgress progress = loadRenderProgress(store.database(), job);
  ASSERT_EQ(progress.passesDone(), 3u);
  EXPECT_EQ(progress.passes[1].finishedMs, 3000);
  EXPECT_EQ(progress.stopReason, "max_passes");
  // A coordinator restarted between the last pass's end and the job's: nothing is recorded twice.
  const PassEnd again = endRenderPass(store, *store.job(job), spec.spec.asReader(), 4000);
  EXPECT_TRUE(again.recordedBefore);
  EXPECT_EQ(again.stop, PassStop::MaxPasses);
  EXPECT_EQ(loadRenderProgress(store.database(), job).passesDone(), 3u);
}

}  // namespace
}  // namespace portico
