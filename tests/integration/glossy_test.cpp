// Glossy finishes end to end (docs/materials.md): the two glossy reference
// scenes (a polished plastic floor and a copper cabinet; a mirror) rendered
// by real workers conserve every photon and ray, trace paths through their
// glossy surfaces, and give the same image bit for bit on one or two
// workers. (Their images against Mitsuba 3: reference_test.cpp.)
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "tests/integration/service_harness.h"

namespace portico {
namespace {

using namespace harness;

class Glossy : public ::testing::TestWithParam<std::string> {
 protected:
  void SetUp() override {
    dir_ = makeTempDirectory("glossy-" + GetParam());
    const fs::path scene = fs::path(PORTICO_SOURCE_DIR) / "tests" / "scenes" / GetParam() / "scene.json";
    ASSERT_EQ(runCommand({kBin + "portico", "scene", "import", scene.string(), store().string()}, dir_ / "import.log"), 0)
        << readFile(dir_ / "import.log");
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path store() const { return dir_ / "store"; }
  int render(const fs::path& output, int workers) {
    return runCommand({kBin + "portico", "render", store().string(), "-o", output.string(), "--workers",
                       std::to_string(workers), "--photons", "40000", "--spp", "2", "--width", "64", "--height", "64"},
                      output.string() + ".log");
  }
  fs::path dir_;
};

TEST_P(Glossy, ConservesPhotonsAndRaysAndGivesTheSameBitsOnOneOrTwoWorkers) {
  ASSERT_EQ(render(dir_ / "one.exr", 1), 0) << readFile(dir_ / "one.exr.log");
  ASSERT_EQ(render(dir_ / "two.exr", 2), 0) << readFile(dir_ / "two.exr.log");
  const auto one = nlohmann::json::parse(readFile(dir_ / "one.exr.json"));
  const auto two = nlohmann::json::parse(readFile(dir_ / "two.exr.json"));
  expectConservation(one);
  expectConservation(two);
  EXPECT_EQ(one["photons"], two["photons"]);
  // Camera and gather paths went on from the glossy surfaces.
  EXPECT_GT(one["rays"]["glossy"].get<int64_t>(), 64 * 64 / 4);   // measured: 10 192 and 1 682
  EXPECT_EQ(one["rays"]["glossy"], two["rays"]["glossy"]);
  EXPECT_EQ(differingFloats(dir_ / "one.exr", dir_ / "two.exr"), 0u);
}

INSTANTIATE_TEST_SUITE_P(Scenes, Glossy, ::testing::Values("glossy_cabinet", "mirror_room"));

}  // namespace
}  // namespace portico
