// Albedo textures end to end: a small room whose floor is a 2 x 2 checker
// (an OBJ with map_Kd, made here) imported and rendered by the real programs;
// the same room untextured for comparison; the same bits with 1 and 2
// workers; a worker within its --memory while the textures are larger than
// it; and a worker that gets the store over the wire fetching the texture.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <cmath>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "common/image/png_file.h"
#include "common/math.h"
#include "tests/integration/service_harness.h"
#include "tests/support/process_memory.h"

namespace portico {
namespace {

using namespace harness;

// Four corners, wound so that cross(b - a, c - a) is the quad's front.
struct Quad {
  Vec3 a, b, c, d;
};

// A closed room x in [-1, 1], y in [0, 2], z in [-1, 1] facing inwards, a
// lamp under the ceiling, and a floor whose uvs put the image upright seen
// from above with -z up (u = (x + 1) / 2, v = (1 - z) / 2). `floorMaterial`
// is the MTL's floor material: with map_Kd or without.
void writeRoom(const fs::path& dir, const std::string& floorMaterial, const std::string& camera) {
  std::ofstream mtl(dir / "room.mtl");
  mtl << "newmtl floor\n" << floorMaterial << "\nnewmtl wall\nKd 0.7 0.7 0.7\nnewmtl lamp\nKd 0 0 0\nKe 10 10 10\n";
  const std::vector<std::pair<std::string, Quad>> quads = {
      {"wall", {{-1, 2, -1}, {1, 2, -1}, {1, 2, 1}, {-1, 2, 1}}},       // ceiling
      {"wall", {{-1, 0, -1}, {-1, 2, -1}, {-1, 2, 1}, {-1, 0, 1}}},     // x = -1
      {"wall", {{1, 0, -1}, {1, 0, 1}, {1, 2, 1}, {1, 2, -1}}},         // x = +1
      {"wall", {{-1, 0, -1}, {1, 0, -1}, {1, 2, -1}, {-1, 2, -1}}},     // z = -1
      {"wall", {{-1, 0, 1}, {-1, 2, 1}, {1, 2, 1}, {1, 0, 1}}},         // z = +1
      {"lamp", {{-0.25f, 1.99f, -0.25f}, {0.25f, 1.99f, -0.25f}, {0.25f, 1.99f, 0.25f}, {-0.25f, 1.99f, 0.25f}}},
  };
  std::ofstream obj(dir / "room.obj");
  obj << "mtllib room.mtl\n";
  int vertex = 1;
  for (const auto& [material, q] : quads) {
    obj << "o " << material << vertex << "\nusemtl " << material << "\n";
    for (const Vec3& p : {q.a, q.b, q.c, q.d}) obj << "v " << p.x << " " << p.y << " " << p.z << "\n";
    obj << "f " << vertex << " " << vertex + 1 << " " << vertex + 2 << "\nf " << vertex << " " << vertex + 2 << " "
        << vertex + 3 << "\n";
    vertex += 4;
  }
  obj << "o floor\nusemtl floor\nv -1 0 -1\nv -1 0 1\nv 1 0 1\nv 1 0 -1\nvt 0 1\nvt 0 0\nvt 1 0\nvt 1 1\n"
      << "f " << vertex << "/1 " << vertex + 1 << "/2 " << vertex + 2 << "/3\nf " << vertex << "/1 " << vertex + 2
      << "/3 " << vertex + 3 << "/4\n";
  std::ofstream building(dir / "building.json");
  building << R"({"objects": [{"obj": "room.obj"}], "camera": )" << camera << "}\n";
}

// From just under the lamp, looking straight down with -z up: the floor fills the view.
const std::string kTopView =
    R"({"origin": [0, 1.8, 0], "target": [0, 0, 0], "up": [0, 0, -1], "fov_y_deg": 50, "width": 64, "height": 64})";

// size x size pixels, 2 x 2 squares: dark top-left and bottom-right.
void writeChecker(const fs::path& path, uint32_t size) {
  std::vector<uint8_t> rgb(size_t(size) * size * 3);
  for (uint32_t y = 0; y < size; ++y)
    for (uint32_t x = 0; x < size; ++x) {
      const bool dark = (x < size / 2) == (y < size / 2);
      for (int c = 0; c < 3; ++c) rgb[(size_t(y) * size + x) * 3 + c] = dark ? 20 : 235;
    }
  writePng(path.string(), size, size, rgb);
}

std::string importRoom(const fs::path& dir, const std::string& floorMaterial) {
  fs::create_directories(dir);
  writeRoom(dir, floorMaterial, kTopView);
  const int code = runCommand(
      {kBin + "portico", "scene", "import", (dir / "building.json").string(), (dir / "store").string()},
      dir / "import.log");
  return code == 0 ? std::string() : readFile(dir / "import.log");
}

int render(const fs::path& store, const fs::path& image, int workers, const std::vector<std::string>& extra = {}) {
  std::vector<std::string> argv{kBin + "portico", "render", store.string(), "-o", image.string(), "--workers",
                                std::to_string(workers), "--photons", "20000", "--spp", "2"};
  argv.insert(argv.end(), extra.begin(), extra.end());
  return runCommand(argv, image.string() + ".log");
}

// The mean luminance of the pixels [x0, x1) x [y0, y1).
double meanOf(const LinearImage& image, uint32_t x0, uint32_t x1, uint32_t y0, uint32_t y1) {
  double sum = 0;
  for (uint32_t y = y0; y < y1; ++y)
    for (uint32_t x = x0; x < x1; ++x)
      for (int c = 0; c < 3; ++c) sum += image.rgb[(size_t(y) * image.width + x) * 3 + c];
  return sum / (3.0 * (x1 - x0) * (y1 - y0));
}

class Textures : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = makeTempDirectory("Textures");
    fs::create_directories(dir_ / "textured");
    writeChecker(dir_ / "textured" / "checker.png", 8);
    textured_ = importRoom(dir_ / "textured", "Kd 1 1 1\nmap_Kd checker.png");
    plain_ = importRoom(dir_ / "plain", "Kd 1 1 1");
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  static inline fs::path dir_;
  static inline std::string textured_, plain_;   // import logs of failed imports
};

TEST_F(Textures, AFloorShowsItsCheckerWhereItsUvsPutIt) {
  ASSERT_EQ(textured_, "");
  ASSERT_EQ(plain_, "");
  const fs::path texturedImage = dir_ / "textured.exr", plainImage = dir_ / "plain.exr";
  ASSERT_EQ(render(dir_ / "textured" / "store", texturedImage, 1), 0) << readFile(texturedImage.string() + ".log");
  ASSERT_EQ(render(dir_ / "plain" / "store", plainImage, 1), 0) << readFile(plainImage.string() + ".log");
  const LinearImage textured = readImage(texturedImage.string()), plain = readImage(plainImage.string());
  ASSERT_EQ(textured.width, 64u);
  // Each quadrant's inside, away from the bilinear seam in the middle: the
  // dark squares (20/255 sRGB: 0.7 % reflectance) under a tenth of the plain
  // floor, the light ones (235/255: 83 %) at least 60 % of it.
  const uint32_t lo[2] = {6, 38}, hi[2] = {26, 58};
  for (int qy = 0; qy < 2; ++qy)
    for (int qx = 0; qx < 2; ++qx) {
      const double ratio = meanOf(textured, lo[qx], hi[qx], lo[qy], hi[qy]) / meanOf(plain, lo[qx], hi[qx], lo[qy], hi[qy]);
      const bool dark = qx == qy;
      std::cout << "quadrant (" << qx << ", " << qy << "): textured / plain " << ratio << "\n";
      if (dark)
        EXPECT_LT(ratio, 0.1) << "quadrant " << qx << "," << qy;
      else
        EXPECT_GT(ratio, 0.6) << "quadrant " << qx << "," << qy;
      EXPECT_LT(ratio, 1.0) << "quadrant " << qx << "," << qy;
    }
  const auto stats = nlohmann::json::parse(readFile(texturedImage.string() + ".json"));
  expectConservation(stats);
}

TEST_F(Textures, OneAndTwoWorkersGiveTheSameBits) {
  ASSERT_EQ(textured_, "");
  const fs::path one = dir_ / "one.exr", two = dir_ / "two.exr";
  ASSERT_EQ(render(dir_ / "textured" / "store", one, 1), 0) << readFile(one.string() + ".log");
  ASSERT_EQ(render(dir_ / "textured" / "store", two, 2), 0) << readFile(two.string() + ".log");
  EXPECT_EQ(differingFloats(one, two), 0u);
}

// size x size RGB texels that a zlib'd PNG holds in little room: gradients
// and a checker of 64-texel squares.
void writeLargeTexture(const fs::path& path, uint32_t size) {
  std::vector<uint8_t> rgb(size_t(size) * size * 3);
  for (uint32_t y = 0; y < size; ++y)
    for (uint32_t x = 0; x < size; ++x) {
      uint8_t* texel = &rgb[(size_t(y) * size + x) * 3];
      texel[0] = uint8_t(x * 255 / size);
      texel[1] = uint8_t(y * 255 / size);
      texel[2] = ((x / 64 + y / 64) % 2) ? 220 : 40;
    }
  writePng(path.string(), size, size, rgb);
}

// 8448 x 8448 texels, 204 MiB as RGB bytes (more as the tile cache holds
// them), against a worker of 192 MiB in all, of which OpenImageIO's code
// takes about 115. A worker of 96 MiB has no room for that code: it refuses
// the leases, saying so, and the job fails.
TEST_F(Textures, AWorkerStaysWithinItsMemoryWhileTheTexturesAreLargerThanIt) {
  const fs::path dir = dir_ / "large";
  fs::create_directories(dir);
  constexpr uint32_t kSize = 8448;
  const uint64_t budget = uint64_t(192) << 20;
  ASSERT_GT(uint64_t(kSize) * kSize * 3, budget);
  writeLargeTexture(dir / "large.png", kSize);
  ASSERT_EQ(importRoom(dir, "Kd 1 1 1\nmap_Kd large.png"), "");
  {
    LocalCluster small(dir / "small", 1, {{"--memory", "96MiB"}});
    const auto status = small.render(dir / "store", dir / "small.exr", 20000, 2);
    EXPECT_EQ(status.value("state", ""), "failed") << status.dump(2);
    EXPECT_NE(status.dump().find("too small for textures"), std::string::npos) << status.dump(2);
  }
  LocalCluster cluster(dir / "cluster", 1, {{"--memory", "192MiB"}});
  const auto status = cluster.render(dir / "store", dir / "image.exr", 20000, 2);
  ASSERT_EQ(status.value("state", ""), "done") << status.dump(2) << readFile(dir / "cluster" / "worker-0.log");
  const uint64_t peak = testing_support::peakResidentBytes(cluster.worker(0).pid());
  std::cout << "worker: peak RSS " << (peak >> 20) << " MiB, --memory " << (budget >> 20) << " MiB, texture "
            << (uint64_t(kSize) * kSize * 3 >> 20) << " MiB\n";
  EXPECT_GT(peak, 0u);
  EXPECT_LE(peak, budget);
  // The worker did load the texture module and count it.
  EXPECT_NE(readFile(dir / "cluster" / "worker-0.log").find("textures: module"), std::string::npos);
  // And the floor shows the texture: its blue checker makes neighbouring
  // 64-texel squares (about 2 cm, 0.7 pixels here) differ, so the image is
  // not the smooth picture of an untextured floor.
  const LinearImage image = readImage((dir / "image.exr").string());
  EXPECT_GT(meanOf(image, 0, image.width, 0, image.height), 0.0);
}

// A worker in its own mount namespace, where an empty tmpfs hides the store:
// it fetches cells and the texture from the coordinator, and renders the
// same bits as a worker reading the store.
TEST_F(Textures, AWorkerWithoutTheStoresFileSystemFetchesTheTextures) {
  ASSERT_EQ(textured_, "");
  const std::string unshare = "/usr/bin/unshare";
  if (runCommand({unshare, "-m", "/bin/true"}, dir_ / "unshare.log") != 0)
    GTEST_SKIP() << "cannot create a mount namespace here (unshare -m): " << readFile(dir_ / "unshare.log");
  const fs::path store = dir_ / "textured" / "store";
  const fs::path local = dir_ / "local", wire = dir_ / "wire";
  {
    LocalCluster cluster(local, 1);
    const auto status = cluster.render(store, local / "image.exr", 20000, 2);
    ASSERT_EQ(status.value("state", ""), "done") << status.dump(2);
  }
  {
    LocalCluster cluster(wire, 0);
    cluster.addWorker({"--cache-dir", (wire / "cache").string()}, [&](std::vector<std::string> argv) {
      std::string command = "mount -t tmpfs none '" + dir_.string() + "' && exec";
      for (const std::string& a : argv) command += " '" + a + "'";
      return std::vector<std::string>{unshare, "-m", "/bin/sh", "-c", command};
    });
    const auto status = cluster.render(store, wire / "image.exr", 20000, 2);
    ASSERT_EQ(status.value("state", ""), "done") << status.dump(2) << readFile(wire / "worker-0.log");
  }
  EXPECT_EQ(differingFloats(local / "image.exr", wire / "image.exr"), 0u);
}

}  // namespace
}  // namespace portico
