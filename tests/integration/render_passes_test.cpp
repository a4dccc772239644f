// Progressive rendering (`--target-error`, `--time-limit`, `--max-passes`)
// end to end, on tests/scenes/cornell_closed with real coordinators and
// workers: passes until the target, measured against the path-traced
// reference; the same bits for the same passes whatever the worker count;
// a time limit; refusals; and a coordinator killed between passes.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "common/image/image_compare.h"
#include "tests/integration/service_harness.h"

namespace portico {
namespace {

using namespace harness;

const fs::path kCornell = fs::path(PORTICO_SOURCE_DIR) / "tests" / "scenes" / "cornell_closed";

class RenderPasses : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = makeTempDirectory("render-passes");
    store_ = dir_ / "cornell";
    ASSERT_EQ(runCommand({kBin + "portico", "scene", "import", (kCornell / "scene.json").string(), store_.string()},
                         dir_ / "import.log"),
              0)
        << readFile(dir_ / "import.log");
  }
  // `portico render` of the Cornell box with few photons and one sample
  // per pixel per pass; returns the exit code.
  static int render(const std::string& name, int workers, const std::vector<std::string>& extra) {
    std::vector<std::string> argv{kBin + "portico", "render", store_.string(), "-o", image(name).string(), "--workers",
                                  std::to_string(workers), "--photons", "50000", "--spp", "1", "--gather", "2"};
    argv.insert(argv.end(), extra.begin(), extra.end());
    return runCommand(argv, dir_ / (name + ".log"));
  }
  static fs::path image(const std::string& name) { return dir_ / (name + ".exr"); }
  static nlohmann::json passes(const std::string& name) {
    return nlohmann::json::parse(readFile(image(name).string() + ".json"))["render_passes"];
  }
  static inline fs::path dir_, store_;
};

TEST_F(RenderPasses, ALooserTargetTakesFewerPassesAndTheMeasuredErrorIsWithinOneAndAHalfTimesTheTarget) {
  const LinearImage reference = readImage((kCornell / "reference.exr").string());
  std::vector<int> passesTaken;
  std::vector<double> relativeMses;
  for (const double target : {0.03, 0.015}) {
    const std::string name = "target-" + std::to_string(target);
    ASSERT_EQ(render(name, 2, {"--target-error", std::to_string(target)}), 0) << readFile(dir_ / (name + ".log"));
    const auto stats = passes(name);
    EXPECT_EQ(stats["stopped"], "target_met") << stats.dump();
    EXPECT_LE(stats["error_estimate"].get<double>(), target);
    EXPECT_TRUE(stats["error_estimates"][0].is_null());   // one pass has no spread to estimate from
    passesTaken.push_back(stats["done"].get<int>());
    const ImageComparison measured = compareImages(readImage(image(name).string()), reference);
    std::cout << "target " << target << ": " << passesTaken.back() << " passes, estimate "
              << stats["error_estimate"].get<double>() << "; " << describe(measured) << "\n";
    EXPECT_LE(measured.blockRmse, 1.5 * target) << describe(measured);
    EXPECT_LE(measured.meanRelativeError, 0.03) << describe(measured);
    relativeMses.push_back(measured.relativeMse);
  }
  EXPECT_GE(passesTaken[0], 2);
  EXPECT_LT(passesTaken[0], passesTaken[1]);
  // More passes average more samples into every pixel: the per-pixel error falls too.
  EXPECT_LT(relativeMses[1], relativeMses[0]);
}

TEST_F(RenderPasses, TheSameNumberOfPassesGivesTheSameBitsWithOneAndTwoWorkers) {
  const std::vector<std::string> small{"--width", "64", "--height", "64"};
  auto three = small;
  three.insert(three.end(), {"--max-passes", "3"});
  auto one = small;
  one.insert(one.end(), {"--max-passes", "1"});
  ASSERT_EQ(render("three-1w", 1, three), 0) << readFile(dir_ / "three-1w.log");
  ASSERT_EQ(render("three-2w", 2, three), 0) << readFile(dir_ / "three-2w.log");
  ASSERT_EQ(render("one", 2, one), 0) << readFile(dir_ / "one.log");
  ASSERT_EQ(render("plain", 2, small), 0) << readFile(dir_ / "plain.log");
  EXPECT_EQ(passes("three-1w")["done"], 3);
  EXPECT_EQ(passes("three-1w")["stopped"], "max_passes");
  EXPECT_EQ(differingFloats(image("three-1w"), image("three-2w")), 0u);
  // One pass is the render without options; three passes differ from it
  // (their own seeds), and their average is less noisy.
  EXPECT_EQ(differingFloats(image("one"), image("plain")), 0u);
  EXPECT_GT(differingFloats(image("three-1w"), image("plain")), 0u);
  EXPECT_EQ(passes("plain")["done"], 1);
}

TEST_F(RenderPasses, ATimeLimitStopsBeforeAPassWouldEndPastItAfterAtLeastOnePass) {
  const std::vector<std::string> small{"--width", "64", "--height", "64", "--max-passes", "4096"};
  auto limited = small;
  limited.insert(limited.end(), {"--time-limit", "3"});
  ASSERT_EQ(render("limited", 2, limited), 0) << readFile(dir_ / "limited.log");
  const auto stats = passes("limited");
  EXPECT_EQ(stats["stopped"], "time_limit") << stats.dump();
  EXPECT_LT(stats["done"].get<int>(), 4096);
  const auto& ends = stats["ends_ms"];
  ASSERT_EQ(ends.size(), stats["done"].get<size_t>());
  // The first pass (which also builds the photon maps) predicts the second:
  // under 1.5 s, a second pass fits in the 3 s.
  if (ends[0].get<int64_t>() <= 1500) {
    ASSERT_GE(ends.size(), 2u) << stats.dump();
    // The passes ended within the limit, give or take the prediction's error (a pass or two).
    const int64_t last = ends.back().get<int64_t>();
    const int64_t pass = last - ends[ends.size() - 2].get<int64_t>();
    EXPECT_LE(last, 3000 + 2 * pass) << stats.dump();
  }

  auto instant = small;
  instant.insert(instant.end(), {"--time-limit", "0.001"});
  ASSERT_EQ(render("instant", 2, instant), 0) << readFile(dir_ / "instant.log");
  EXPECT_EQ(passes("instant")["done"], 1);
  EXPECT_EQ(passes("instant")["stopped"], "time_limit");
}

// The client refuses in one line naming the option (CLI11's --help hint may
// follow); the coordinator refuses a hand-made submit in one line too.
TEST_F(RenderPasses, BadValuesAreRefusedInOneLineByTheClientAndByTheCoordinator) {
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases{
      {{"--target-error", "0"}, "--target-error"},  {{"--target-error", "-0.01"}, "--target-error"},
      {{"--target-error", "nan"}, "--target-error"}, {{"--target-error", "2"}, "--target-error"},
      {{"--time-limit", "0"}, "--time-limit"},       {{"--time-limit", "-3"}, "--time-limit"},
      {{"--time-limit", "nan"}, "--time-limit"},     {{"--max-passes", "0"}, "--max-passes"},
      {{"--max-passes", "-1"}, "--max-passes"},
  };
  int index = 0;
  for (const auto& [options, option] : cases) {
    const std::string name = "bad-" + std::to_string(index++);
    EXPECT_NE(render(name, 1, options), 0) << options[0] << " " << options[1];
    const std::string log = readFile(dir_ / (name + ".log"));
    const size_t end = log.find('\n');
    const std::string first = log.substr(0, end), rest = end == std::string::npos ? "" : log.substr(end + 1);
    EXPECT_NE(first.find(option), std::string::npos) << log;
    EXPECT_TRUE(rest.empty() || rest == "Run with --help for more information.\n") << log;
  }

  LocalCluster cluster(dir_ / "refusals", 0);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<std::pair<std::function<void(wire::JobSpec::Builder)>, std::string>> submits{
      {[](wire::JobSpec::Builder spec) { spec.getTargetError().setValue(0); }, "target error"},
      {[](wire::JobSpec::Builder spec) { spec.getTargetError().setValue(-0.5); }, "target error"},
      {[nan](wire::JobSpec::Builder spec) { spec.getTargetError().setValue(nan); }, "target error"},
      {[](wire::JobSpec::Builder spec) { spec.getTimeLimit().setSeconds(0); }, "time limit"},
      {[nan](wire::JobSpec::Builder spec) { spec.getTimeLimit().setSeconds(nan); }, "time limit"},
      {[](wire::JobSpec::Builder spec) { spec.setMaxPasses(1u << 30); }, "max passes"},
  };
  for (const auto& [adjust, what] : submits) {
    try {
      cluster.submit(store_, dir_ / "refused.exr", 1000, 1, adjust);
      ADD_FAILURE() << what << ": accepted";
    } catch (const std::exception& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find(what), std::string::npos) << message;
      EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    }
  }
}

// Killed during a pass, the coordinator resumes the pass in progress with
// its seed: the image has the bits of an uninterrupted run.
TEST_F(RenderPasses, AKilledCoordinatorResumesThePassesWithTheSameBits) {
  const auto tenPasses = [](wire::JobSpec::Builder spec) { spec.setMaxPasses(10); };
  {
    LocalCluster cluster(dir_ / "whole", 2);
    const auto status = cluster.wait(cluster.submit(store_, dir_ / "whole.exr", 50000, 4, tenPasses));
    ASSERT_EQ(status.value("state", ""), "done") << status.dump(2);
  }
  const fs::path dir = dir_ / "killed";
  LocalCluster cluster(dir, 2);
  const std::string endpoint = cluster.endpoint();
  const uint64_t job = cluster.submit(store_, dir_ / "killed.exr", 50000, 4, tenPasses);
  ASSERT_TRUE(waitUntil([&] { return cluster.status(job)["render_passes"].value("done", 0) >= 2; },
                        std::chrono::seconds(60)));
  cluster.killCoordinator();
  ASSERT_LT(nlohmann::json::parse(readFile(dir_ / "killed.exr.json"))["render_passes"].value("done", 0), 10)
      << "the job ended before the coordinator was killed";
  cluster.startCoordinator(endpoint);
  const auto status = cluster.wait(job);
  ASSERT_EQ(status.value("state", ""), "done") << status.dump(2);
  EXPECT_EQ(status["render_passes"]["done"], 10);
  EXPECT_EQ(differingFloats(dir_ / "whole.exr", dir_ / "killed.exr"), 0u);
}

}  // namespace
}  // namespace portico
