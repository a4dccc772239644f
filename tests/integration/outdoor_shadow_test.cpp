// Geometry outdoors shadows daylight: a room with a window in its east wall
// under an overhang standing in the outdoor cell, lit by a low sun from the
// east. The overhang takes most of the sun patch off the floor (against the
// same room without it), a point deep in its shadow gets no direct sun,
// photons are conserved with daylight photons blocked outdoors, and the
// image is the same bit for bit on one or two workers.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <array>
#include <cmath>
#include <fstream>

#include "common/image/image_reader.h"
#include "tests/integration/service_harness.h"

namespace portico {
namespace {

using namespace harness;
using Quad = std::array<std::array<float, 3>, 4>;

// The room: x in [0, 4], y in [0, 2.5], z in [-1.5, 1.5]; the window in its
// east wall (x = 4): y in [0.5, 2], z in [-1, 1].
constexpr float kSill = 0.5f, kHead = 2.0f, kHalfWidth = 1.0f;

void writeQuads(const fs::path& path, const std::vector<Quad>& quads) {
  std::ofstream out(path);
  for (const Quad& q : quads)
    for (const auto& v : q) out << "v " << v[0] << ' ' << v[1] << ' ' << v[2] << '\n';
  for (size_t i = 0; i < quads.size(); ++i) {
    const size_t b = 4 * i + 1;
    out << "f " << b << ' ' << b + 1 << ' ' << b + 2 << '\n' << "f " << b << ' ' << b + 2 << ' ' << b + 3 << '\n';
  }
}

// Writes building.json (and its OBJ files) into `dir`; with `overhang`, a
// 2 m deep slab at 2.2 m over the window in the outdoor cell.
fs::path writeBuilding(const fs::path& dir, bool overhang) {
  fs::create_directories(dir);
  writeQuads(dir / "floor.obj", {{{{0, 0, -1.5f}, {0, 0, 1.5f}, {4, 0, 1.5f}, {4, 0, -1.5f}}}});
  writeQuads(dir / "ceiling.obj", {{{{0, 2.5f, -1.5f}, {4, 2.5f, -1.5f}, {4, 2.5f, 1.5f}, {0, 2.5f, 1.5f}}}});
  writeQuads(dir / "walls.obj",
             {{{{0, 0, -1.5f}, {4, 0, -1.5f}, {4, 2.5f, -1.5f}, {0, 2.5f, -1.5f}}},
              {{{0, 0, 1.5f}, {0, 2.5f, 1.5f}, {4, 2.5f, 1.5f}, {4, 0, 1.5f}}},
              {{{0, 0, -1.5f}, {0, 2.5f, -1.5f}, {0, 2.5f, 1.5f}, {0, 0, 1.5f}}},
              // The east wall round the window.
              {{{4, 0, -1.5f}, {4, 0, 1.5f}, {4, kSill, 1.5f}, {4, kSill, -1.5f}}},
              {{{4, kHead, -1.5f}, {4, kHead, 1.5f}, {4, 2.5f, 1.5f}, {4, 2.5f, -1.5f}}},
              {{{4, kSill, -1.5f}, {4, kSill, -kHalfWidth}, {4, kHead, -kHalfWidth}, {4, kHead, -1.5f}}},
              {{{4, kSill, kHalfWidth}, {4, kSill, 1.5f}, {4, kHead, 1.5f}, {4, kHead, kHalfWidth}}}});
  writeQuads(dir / "overhang.obj", {{{{4.001f, 2.2f, -2}, {4.001f, 2.2f, 2}, {6, 2.2f, 2}, {6, 2.2f, -2}}}});
  nlohmann::json objects = nlohmann::json::array();
  for (const char* name : {"floor", "ceiling", "walls"})
    objects.push_back({{"obj", std::string(name) + ".obj"}, {"cell", "room"}, {"albedo", {0.5, 0.5, 0.5}}});
  if (overhang) objects.push_back({{"obj", "overhang.obj"}, {"cell", "outside"}, {"albedo", {0.3, 0.3, 0.3}}});
  const nlohmann::json window = {{4, kSill, -kHalfWidth}, {4, kSill, kHalfWidth}, {4, kHead, kHalfWidth},
                                 {4, kHead, -kHalfWidth}};
  const nlohmann::json building = {
      {"name", "overhang"},
      {"cells",
       {{{"name", "room"}, {"aabb", {{"min", {0, 0, -1.5}}, {"max", {4, 2.5, 1.5}}}}},
        {{"name", "outside"}, {"aabb", {{"min", {4, -1, -3}}, {"max", {8, 4, 3}}}}}}},
      {"portals", {{{"between", {"room", "outside"}}, {"polygon", window}}}},
      {"objects", objects},
      // Looking straight down at the floor, +x (the window) at the top.
      {"camera",
       {{"origin", {2, 2.4, 0}}, {"target", {2, 0, 0}}, {"up", {1, 0, 0}}, {"fov_y_deg", 90}, {"width", 48},
        {"height", 48}}}};
  std::ofstream(dir / "building.json") << building.dump(1);
  return dir / "building.json";
}

class OutdoorShadow : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = makeTempDirectory("outdoor-shadow"); }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path import(const std::string& name, bool overhang) {
    const fs::path store = dir_ / (name + "-store");
    const fs::path json = writeBuilding(dir_ / name, overhang);
    EXPECT_EQ(runCommand({kBin + "portico", "scene", "import", json.string(), store.string()}, dir_ / "import.log"), 0)
        << readFile(dir_ / "import.log");
    return store;
  }
  // The sun from the east, 35 degrees up.
  int render(const fs::path& store, const fs::path& output, int workers, const std::string& sky) {
    return runCommand({kBin + "portico", "render", store.string(), "-o", output.string(), "--workers",
                       std::to_string(workers), "--photons", "20000", "--spp", "4", "--sun", "90,35",
                       "--sun-irradiance", "10,10,10", "--sky", sky},
                      output.string() + ".log");
  }
  fs::path dir_;
};

// The mean of the floor's pixels between x0 and x1 (metres), |z| < 0.6.
double floorMean(const LinearImage& image, float x0, float x1) {
  double sum = 0;
  int count = 0;
  for (int row = 0; row < int(image.height); ++row) {
    // 90 degrees from 2.4 m up: rows span x = 2 +- 2.4, +x at the top.
    const float x = 2.0f + 2.4f * (1.0f - 2.0f * (row + 0.5f) / image.height);
    if (x < x0 || x > x1) continue;
    for (int column = 0; column < int(image.width); ++column) {
      const float z = 2.4f * (2.0f * (column + 0.5f) / image.width - 1.0f);
      if (std::abs(z) > 0.6f) continue;
      const size_t i = 3 * (size_t(row) * image.width + column);
      sum += (image.rgb[i] + image.rgb[i + 1] + image.rgb[i + 2]) / 3.0;
      ++count;
    }
  }
  return count ? sum / count : 0;
}

TEST_F(OutdoorShadow, AnOverhangShadowsTheSunPatchAndItsShadowGetsNoDirectSun) {
  const fs::path open = import("open", false), covered = import("covered", true);
  ASSERT_EQ(render(open, dir_ / "open.exr", 1, "uniform:0.01,0.01,0.01"), 0) << readFile(dir_ / "open.exr.log");
  ASSERT_EQ(render(covered, dir_ / "covered.exr", 1, "uniform:0.01,0.01,0.01"), 0)
      << readFile(dir_ / "covered.exr.log");
  const LinearImage a = readImage((dir_ / "open.exr").string()), b = readImage((dir_ / "covered.exr").string());
  // Through the open window the sun falls on x in [1.14, 3.29]; under the
  // overhang (its edge 2 m out, 0.2 m above the window's head) only the
  // rays through the window's lowest 0.3 m pass: x in [2.86, 3.29].
  const double patchOpen = floorMean(a, 1.14f, 3.29f), patchCovered = floorMean(b, 1.14f, 3.29f);
  const double shadowOpen = floorMean(a, 1.4f, 2.6f), shadowCovered = floorMean(b, 1.4f, 2.6f);
  const double litOpen = floorMean(a, 2.95f, 3.2f), litCovered = floorMean(b, 2.95f, 3.2f);
  // Direct sun on the floor: 0.5 * 10 * sin 35 / pi = 0.91.
  EXPECT_GT(shadowOpen, 0.7);
  EXPECT_LT(patchCovered, 0.5 * patchOpen);
  // Deep in the overhang's shadow only light reflected in the room is left.
  EXPECT_LT(shadowCovered, 0.05 * shadowOpen) << shadowCovered << " vs " << shadowOpen;
  // Where the sun still passes under the overhang, it is as bright as without.
  EXPECT_GT(litCovered, 0.8 * litOpen) << litCovered << " vs " << litOpen;
}

TEST_F(OutdoorShadow, PhotonsBlockedOutdoorsAreConservedAndTheBitsAreTheSameOnOneOrTwoWorkers) {
  const fs::path covered = import("covered", true), open = import("open", false);
  ASSERT_EQ(render(covered, dir_ / "one.exr", 1, "uniform:0.8,0.9,1.1"), 0) << readFile(dir_ / "one.exr.log");
  ASSERT_EQ(render(covered, dir_ / "two.exr", 2, "uniform:0.8,0.9,1.1"), 0) << readFile(dir_ / "two.exr.log");
  ASSERT_EQ(render(open, dir_ / "open.exr", 1, "uniform:0.8,0.9,1.1"), 0) << readFile(dir_ / "open.exr.log");
  const auto one = nlohmann::json::parse(readFile(dir_ / "one.exr.json"));
  const auto two = nlohmann::json::parse(readFile(dir_ / "two.exr.json"));
  const auto without = nlohmann::json::parse(readFile(dir_ / "open.exr.json"));
  expectConservation(one);
  expectConservation(two);
  EXPECT_EQ(one["photons"], two["photons"]);
  EXPECT_EQ(differingFloats(dir_ / "one.exr", dir_ / "two.exr"), 0u);
  // The same photons start on the window; under the overhang fewer get in,
  // so fewer land on the room's surfaces.
  EXPECT_EQ(one["photons"]["emitted"], without["photons"]["emitted"]);
  EXPECT_LT(one["photons"]["deposits"].get<int64_t>(), without["photons"]["deposits"].get<int64_t>() * 9 / 10);
}

}  // namespace
}  // namespace portico
