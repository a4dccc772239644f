// Daylight end to end: the daylight reference scene (an open and a glazed
// window, sun and sky) rendered by real workers; photons are conserved with
// glass and sky, the image is the same bit for bit on one or two workers,
// and a bad --sun is refused in one line naming it.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstring>
#include <sstream>

#include "common/image/image_reader.h"
#include "tests/integration/service_harness.h"

namespace portico {
namespace {

using namespace harness;

const fs::path kScene = fs::path(PORTICO_SOURCE_DIR) / "tests" / "scenes" / "daylight_window";

std::vector<std::string> renderArgs() {
  std::istringstream in(readFile(kScene / "render_args.txt"));
  std::vector<std::string> args;
  for (std::string word; in >> word;) args.push_back(word);
  return args;
}

class Daylight : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = makeTempDirectory("daylight");
    ASSERT_EQ(runCommand({kBin + "portico", "scene", "import", (kScene / "scene.json").string(), store().string()},
                         dir_ / "import.log"),
              0)
        << readFile(dir_ / "import.log");
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path store() const { return dir_ / "store"; }
  // Renders with the scene's daylight on `workers` workers; returns the exit code.
  int render(const fs::path& output, int workers, std::vector<std::string> extra = {}) {
    std::vector<std::string> argv{kBin + "portico", "render", store().string(), "-o", output.string(), "--workers",
                                  std::to_string(workers), "--photons", "40000", "--spp", "2", "--width", "64",
                                  "--height", "48"};
    for (const std::string& a : renderArgs()) argv.push_back(a);
    argv.insert(argv.end(), extra.begin(), extra.end());
    return runCommand(argv, output.string() + ".log");
  }
  fs::path dir_;
};

TEST_F(Daylight, SunAndSkyThroughGlassConservePhotonsAndGiveTheSameBitsOnOneOrTwoWorkers) {
  ASSERT_EQ(render(dir_ / "one.exr", 1), 0) << readFile(dir_ / "one.exr.log");
  ASSERT_EQ(render(dir_ / "two.exr", 2), 0) << readFile(dir_ / "two.exr.log");
  const auto one = nlohmann::json::parse(readFile(dir_ / "one.exr.json"));
  const auto two = nlohmann::json::parse(readFile(dir_ / "two.exr.json"));
  expectConservation(one);
  expectConservation(two);
  EXPECT_EQ(one["photons"], two["photons"]);
  // Light left through the windows, and photons crossed into the outside.
  EXPECT_GT(one["photons"]["escaped"].get<int64_t>(), 0);
  EXPECT_EQ(one["photons"]["emitted"].get<int64_t>(), 40000);
  const LinearImage a = readImage((dir_ / "one.exr").string()), b = readImage((dir_ / "two.exr").string());
  ASSERT_EQ(a.rgb.size(), b.rgb.size());
  size_t differing = 0, lit = 0;
  for (size_t i = 0; i < a.rgb.size(); ++i) {
    differing += std::memcmp(&a.rgb[i], &b.rgb[i], sizeof(float)) != 0;
    lit += a.rgb[i] > 0;
  }
  EXPECT_EQ(differing, 0u);
  EXPECT_GT(lit, a.rgb.size() * 9 / 10);   // a closed room lit by daylight alone
}

TEST_F(Daylight, ABadSunIsRefusedInOneLineNamingTheOption) {
  std::vector<std::string> argv{kBin + "portico", "render", store().string(), "-o", (dir_ / "bad.exr").string(),
                                "--sun", "400,-5"};
  EXPECT_NE(runCommand(argv, dir_ / "bad.log"), 0);
  const std::string log = readFile(dir_ / "bad.log");
  EXPECT_NE(log.find("--sun"), std::string::npos) << log;
  EXPECT_NE(log.find("400"), std::string::npos) << log;
  EXPECT_FALSE(fs::exists(dir_ / "bad.exr"));
  argv.back() = "40";   // one number
  EXPECT_NE(runCommand(argv, dir_ / "one-number.log"), 0);
  EXPECT_NE(readFile(dir_ / "one-number.log").find("AZIMUTH,ELEVATION"), std::string::npos)
      << readFile(dir_ / "one-number.log");
}

}  // namespace
}  // namespace portico
