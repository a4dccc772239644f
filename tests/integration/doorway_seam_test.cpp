// A floor running through a portal shows no step in brightness: the same
// hall rendered as two cells joined by an open portal and as one cell gives
// the same floor, band by band, right up to the portal line. Without the
// photons copied across the portal, each side's density estimate near the
// line would see only half a disc of photons and drop by up to half.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "common/image/image_reader.h"
#include "common/util/child_process.h"
#include "tests/support/temp_directory.h"

namespace portico {
namespace {

namespace fs = std::filesystem;
const std::string kBin = std::string(PORTICO_BINARY_DIR) + "/bin/";

std::string readFile(const fs::path& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// A quad as two triangles, counter-clockwise seen from the side it faces.
void writeQuad(const fs::path& path, const std::array<std::array<float, 3>, 4>& corners) {
  std::ofstream out(path);
  for (const auto& c : corners) out << "v " << c[0] << " " << c[1] << " " << c[2] << "\n";
  out << "f 1 2 3\nf 1 3 4\n";
}

// The hall x in [-4, 4], y in [0, 2.5], z in [-1.5, 1.5], its shell split at
// x = 0 into halves "west" and "east"; one light in the west half.
void writeHall(const fs::path& dir, bool twoCells) {
  const float h = 2.5f;
  struct Half { std::string name; float x0, x1; };
  nlohmann::json objects = nlohmann::json::array();
  for (const Half& half : {Half{"west", -4, 0}, Half{"east", 0, 4}}) {
    const float a = half.x0, b = half.x1;
    auto add = [&](const std::string& what, const std::array<std::array<float, 3>, 4>& quad, std::array<float, 3> albedo) {
      const std::string file = half.name + "_" + what + ".obj";
      writeQuad(dir / file, quad);
      nlohmann::json object{{"obj", file}, {"name", half.name + "_" + what}, {"albedo", albedo}, {"emission", nullptr}};
      if (twoCells) object["cell"] = half.name;
      objects.push_back(object);
    };
    add("floor", {{{a, 0, -1.5f}, {a, 0, 1.5f}, {b, 0, 1.5f}, {b, 0, -1.5f}}}, {0.6f, 0.6f, 0.6f});
    add("ceiling", {{{a, h, -1.5f}, {b, h, -1.5f}, {b, h, 1.5f}, {a, h, 1.5f}}}, {0.7f, 0.7f, 0.7f});
    add("north", {{{a, 0, -1.5f}, {b, 0, -1.5f}, {b, h, -1.5f}, {a, h, -1.5f}}}, {0.5f, 0.5f, 0.5f});
    add("south", {{{a, 0, 1.5f}, {a, h, 1.5f}, {b, h, 1.5f}, {b, 0, 1.5f}}}, {0.5f, 0.5f, 0.5f});
    const float end = half.name == "west" ? -4.0f : 4.0f;
    if (end < 0)
      add("end", {{{end, 0, -1.5f}, {end, h, -1.5f}, {end, h, 1.5f}, {end, 0, 1.5f}}}, {0.5f, 0.5f, 0.5f});
    else
      add("end", {{{end, 0, -1.5f}, {end, 0, 1.5f}, {end, h, 1.5f}, {end, h, -1.5f}}}, {0.5f, 0.5f, 0.5f});
  }
  // Light facing down near the ceiling of the west half.
  writeQuad(dir / "light.obj", {{{-1.6f, h - 0.001f, -0.3f}, {-1.0f, h - 0.001f, -0.3f}, {-1.0f, h - 0.001f, 0.3f},
                                  {-1.6f, h - 0.001f, 0.3f}}});
  nlohmann::json light{{"obj", "light.obj"}, {"name", "light"}, {"albedo", {0, 0, 0}}, {"emission", {20, 20, 20}}};
  if (twoCells) light["cell"] = "west";
  objects.push_back(light);
  nlohmann::json building{{"units", "metres"},
                          {"objects", objects},
                          {"camera",
                           {{"origin", {0.5, 2.3, 0}},
                            {"target", {0.5, 0, 0}},
                            {"up", {0, 0, -1}},
                            {"fov_y_deg", 90},
                            {"width", 96},
                            {"height", 64}}}};
  if (twoCells) {
    building["cells"] = {{{"name", "west"}, {"aabb", {{"min", {-4, 0, -1.5}}, {"max", {0, h, 1.5}}}}},
                         {{"name", "east"}, {"aabb", {{"min", {0, 0, -1.5}}, {"max", {4, h, 1.5}}}}}};
    building["portals"] = {{{"between", {"west", "east"}},
                            {"polygon", {{0, 0, -1.5}, {0, 0, 1.5}, {0, h, 1.5}, {0, h, -1.5}}}}};
  }
  std::ofstream(dir / "building.json") << building.dump(2);
}

LinearImage renderHall(const fs::path& dir, bool twoCells, int gather) {
  fs::create_directories(dir);
  writeHall(dir, twoCells);
  ChildProcess importer({kBin + "portico", "scene", "import", (dir / "building.json").string(), (dir / "store").string()},
                        (dir / "log").string());
  EXPECT_EQ(importer.wait(), 0) << readFile(dir / "log");
  ChildProcess render({kBin + "portico", "render", (dir / "store").string(), "-o", (dir / "floor.exr").string(),
                       "--gather", std::to_string(gather), "--spp", "4", "--photons", "200000", "--seed", "5"},
                      (dir / "log").string());
  EXPECT_EQ(render.wait(), 0) << readFile(dir / "log");
  return readImage((dir / "floor.exr").string());
}

// --gather 0: the photon map is seen directly, where a seam would show most;
// --gather 4: gather hits read the precomputed irradiance of the cell they
// land in, whose points near the portal were estimated from both sides.
class DoorwaySeam : public ::testing::TestWithParam<int> {};

TEST_P(DoorwaySeam, FloorThroughAPortalHasNoStep) {
  const int gather = GetParam();
  const fs::path dir = testing_support::tempPath("seam-" + std::to_string(gather));
  const LinearImage split = renderHall(dir / "two-cells", true, gather);
  const LinearImage whole = renderHall(dir / "one-cell", false, gather);
  ASSERT_EQ(split.width, 96u);
  // The camera looks straight down from x = 0.5 with a 90 degree vertical
  // field: image column c sees floor x = 0.5 + (2c/W - 1) * tan_x * 2.3.
  const double tanX = 96.0 / 64.0;
  auto columnOf = [&](double x) { return int(std::floor(((x - 0.5) / (2.3 * tanX) + 1) * 96 / 2)); };
  const int portalColumn = columnOf(0.0);
  ASSERT_GT(portalColumn, 4);
  // Mean floor radiance of 3-column bands on both sides of the portal line,
  // over the middle rows, for both renders.
  auto band = [](const LinearImage& image, int c0, int c1) {
    double sum = 0;
    int n = 0;
    for (uint32_t y = 16; y < 48; ++y)
      for (int c = c0; c < c1; ++c)
        for (int k = 0; k < 3; ++k, ++n) sum += image.rgb[(y * image.width + c) * 3 + k];
    return sum / n;
  };
  for (int offset : {-6, -3, 0, 3}) {
    const int c0 = portalColumn + offset, c1 = c0 + 3;
    const double a = band(split, c0, c1), b = band(whole, c0, c1);
    EXPECT_GT(b, 0.0);
    EXPECT_NEAR(a / b, 1.0, 0.02) << "band at columns " << c0 << ".." << c1 << " (portal at " << portalColumn << ")";
  }
  fs::remove_all(dir);
}

INSTANTIATE_TEST_SUITE_P(Gather, DoorwaySeam, ::testing::Values(0, 4),
                         [](const auto& info) { return "gather" + std::to_string(info.param); });

}  // namespace
}  // namespace portico
