// Lamps in photometric terms, rendered by `portico render`:
//  * an IES luminaire over a large diffuse floor: every pixel's radiance is
//    rho E / pi with E = I(gamma, C) cos(theta) / d^2 (inverse-square and
//    cosine law, the candela function the file samples, asymmetric in C so a
//    wrong orientation shows), within 1 %; the same with a deliberate 5 %
//    error in the expected light fails;
//  * a lamp given as 1000 lm renders the same bits as the lamp given by the
//    radiance those lumens make.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>

#include "common/analysis/false_color_scale.h"
#include "common/image/image_reader.h"
#include "common/photometry/lamp_colour.h"
#include "common/scene/store/scene_store.h"
#include "tests/integration/service_harness.h"

namespace portico {
namespace {

using namespace harness;

constexpr double kDeg = M_PI / 180.0;
constexpr float kHeight = 2.0f;       // the luminaire over the floor
constexpr float kCameraHeight = 1.9f;
constexpr float kAlbedo = 0.5f;

// The candela function the test file samples: a downlight brighter towards C0 (+x).
double candela(double gamma, double c) {
  if (gamma > 90) return 0;
  return (500 + 1000 * std::cos(gamma * kDeg)) * (1 + 0.3 * std::sin(gamma * kDeg) * std::cos(c * kDeg));
}

void writeIes(const fs::path& path) {
  std::ofstream out(path);
  out << "IESNA:LM-63-2002\n[TEST] portico photometric_lights_test\n[LUMINAIRE] analytic downlight\nTILT=NONE\n";
  const int verticals = 37, horizontals = 73;   // every 2.5 degrees to 90, every 5 to 360
  out << "1 -1 1 " << verticals << ' ' << horizontals << " 1 2 0 0 0\n1 1 10\n";
  for (int v = 0; v < verticals; ++v) out << 2.5 * v << ' ';
  out << '\n';
  for (int h = 0; h < horizontals; ++h) out << 5.0 * h << ' ';
  out << '\n';
  char value[32];
  for (int h = 0; h < horizontals; ++h) {
    for (int v = 0; v < verticals; ++v) {
      std::snprintf(value, sizeof value, "%.6f ", candela(2.5 * v, 5.0 * h));
      out << value;
    }
    out << '\n';
  }
}

void writeFloor(const fs::path& path, float half) {
  std::ofstream out(path);
  out << "v " << -half << " 0 " << -half << "\nv " << -half << " 0 " << half << "\nv " << half << " 0 " << half
      << "\nv " << half << " 0 " << -half << "\nf 1 2 3\nf 1 3 4\n";
}

// Straight down at the floor: +x to the image's right, +z down the image (up is -z).
nlohmann::json camera(int size) {
  return {{"origin", {0, kCameraHeight, 0}}, {"target", {0, 0, 0}}, {"up", {0, 0, -1}}, {"fov_y_deg", 90},
          {"width", size},                   {"height", size}};
}

class PhotometricLights : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = makeTempDirectory("photometric-lights"); }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path import(const std::string& name, const nlohmann::json& building) {
    std::ofstream(dir_ / (name + ".json")) << building.dump(1);
    const fs::path store = dir_ / (name + "-store");
    EXPECT_EQ(runCommand({kBin + "portico", "scene", "import", (dir_ / (name + ".json")).string(), store.string()},
                         dir_ / (name + "-import.log")),
              0)
        << readFile(dir_ / (name + "-import.log"));
    return store;
  }
  LinearImage render(const fs::path& store, const std::string& name, const std::vector<std::string>& extra = {}) {
    const fs::path image = dir_ / (name + ".exr");
    std::vector<std::string> argv{kBin + "portico", "render", store.string(), "-o", image.string(), "--workers", "1",
                                  "--photons", "20000"};
    argv.insert(argv.end(), extra.begin(), extra.end());
    EXPECT_EQ(runCommand(argv, dir_ / (name + ".log")), 0) << readFile(dir_ / (name + ".log"));
    return readImage(image.string());
  }
  fs::path dir_;
};

TEST_F(PhotometricLights, AnIesLuminaireLightsAPlaneByTheInverseSquareAndCosineLaws) {
  writeIes(dir_ / "downlight.ies");
  writeFloor(dir_ / "floor.obj", 50);
  constexpr int kSize = 48;
  const nlohmann::json building = {
      {"name", "ies-plane"},
      {"objects", {{{"obj", "floor.obj"}, {"albedo", {kAlbedo, kAlbedo, kAlbedo}}}}},
      // Aimed down, C0 along +x; "colour" white: 1/179 W/sr per cd in each channel.
      {"lights",
       {{{"name", "downlight"}, {"ies", "downlight.ies"}, {"position", {0, kHeight, 0}}, {"aim", {0, -1, 0}},
         {"c0", {1, 0, 0}}, {"colour", {1, 1, 1}}}}},
      {"camera", camera(kSize)}};
  const fs::path store = import("ies-plane", building);
  // 64 samples a pixel: its mean is then its centre's value (E varies by some 4 % across a pixel).
  const LinearImage image = render(store, "ies-plane", {"--spp", "64"});
  ASSERT_EQ(image.width, uint32_t(kSize));
  // The floor point at a pixel's centre: 90 degrees from 1.9 m up spans +-1.9 m.
  double worst = 0, worstWrong = 1e9;
  int checked = 0;
  for (int row = 2; row < kSize; row += 5)
    for (int column = 1; column < kSize; column += 5) {
      const double x = kCameraHeight * (2.0 * (column + 0.5) / kSize - 1.0);
      const double z = kCameraHeight * (2.0 * (row + 0.5) / kSize - 1.0);
      const double d2 = x * x + z * z + kHeight * kHeight, d = std::sqrt(d2);
      const double cosTheta = kHeight / d;                          // at the floor, and gamma's cosine at the lamp
      const double gamma = std::acos(cosTheta) / kDeg;
      // C90 = cross(C0, nadir) = cross(+x, -y) = -z.
      const double cAngle = std::atan2(-z, x) / kDeg;
      const double illuminance = candela(gamma, cAngle) / 179.0 * cosTheta / d2;   // W/m^2 per channel
      const double expected = kAlbedo * illuminance / M_PI;
      const size_t i = 3 * (size_t(row) * kSize + column);
      for (int channel = 0; channel < 3; ++channel) {
        const double error = std::abs(image.rgb[i + channel] / expected - 1);
        worst = std::max(worst, error);
        worstWrong = std::min(worstWrong, std::abs(image.rgb[i + channel] / (1.05 * expected) - 1));
      }
      ++checked;
    }
  std::printf("  %d floor points: worst error %.3f %% against E = I cos / d^2 (against 5 %% more light: best %.3f %%)\n",
              checked, 100 * worst, 100 * worstWrong);
  EXPECT_LT(worst, 0.01);
  // The check would see a 5 % error in the light at every point.
  EXPECT_GT(worstWrong, 0.01);
}

// `--aov luminance --falsecolor`: the same floor and luminaire, and a lamp
// of radiance (2, 1, 0.5) facing the camera. Every pixel of the EXR is 179 x
// the Rec. 709 Y of the radiance render's pixel (the same light, written in
// cd/m^2); a floor pixel is then rho I cos / (pi d^2) cd/m^2, the lamp 179 x
// Y(L); the false-colour PNG beside it colours each pixel by the scale and
// draws the legend to the right. A PNG output is refused in one line.
TEST_F(PhotometricLights, ALuminanceRenderIsInCdPerSquareMetreWithItsFalseColourPictureBeside) {
  writeIes(dir_ / "downlight.ies");
  writeFloor(dir_ / "floor.obj", 50);
  constexpr int kSize = 48;
  const nlohmann::json lamp = {{"corner", {1.0, 0.01, 1.0}}, {"edge1", {0, 0, 0.6}}, {"edge2", {0.6, 0, 0}}};
  const nlohmann::json building = {
      {"objects", {{{"obj", "floor.obj"}, {"albedo", {kAlbedo, kAlbedo, kAlbedo}}}}},
      {"lights",
       {{{"name", "downlight"}, {"ies", "downlight.ies"}, {"position", {0, kHeight, 0}}, {"colour", {1, 1, 1}}},
        {{"name", "panel"}, {"quad", lamp}, {"radiance", {2, 1, 0.5}}}}},
      {"camera", camera(kSize)}};
  const fs::path store = import("luminance", building);
  const LinearImage radiance = render(store, "radiance", {"--spp", "64"});
  const LinearImage luminance =
      render(store, "luminance", {"--spp", "64", "--aov", "luminance", "--falsecolor", "--falsecolor-max", "100"});
  ASSERT_EQ(luminance.rgb.size(), radiance.rgb.size());
  for (size_t p = 0; p < radiance.rgb.size(); p += 3) {
    const double y = 179.0 * (0.2126 * radiance.rgb[p] + 0.7152 * radiance.rgb[p + 1] + 0.0722 * radiance.rgb[p + 2]);
    ASSERT_NEAR(luminance.rgb[p], y, 1e-5 * (1 + y)) << "pixel " << p / 3;
    ASSERT_EQ(luminance.rgb[p + 1], luminance.rgb[p]);
  }
  // The floor, away from the lamp, against rho I cos / (pi d^2); the lamp's inside, 179 Y(L).
  const auto pixelAt = [&](double x, double z) {
    const int column = int((x / kCameraHeight + 1) / 2 * kSize), row = int((z / kCameraHeight + 1) / 2 * kSize);
    return size_t(row) * kSize + column;
  };
  double worst = 0;
  for (int row = 2; row < kSize; row += 5)
    for (int column = 1; column < kSize / 2; column += 5) {
      const double x = kCameraHeight * (2.0 * (column + 0.5) / kSize - 1.0);
      const double z = kCameraHeight * (2.0 * (row + 0.5) / kSize - 1.0);
      const double d2 = x * x + z * z + kHeight * kHeight, d = std::sqrt(d2);
      const double expected = kAlbedo * candela(std::acos(kHeight / d) / kDeg, std::atan2(-z, x) / kDeg) *
                              (kHeight / d) / (M_PI * d2);
      worst = std::max(worst, std::abs(luminance.rgb[3 * (size_t(row) * kSize + column)] / expected - 1));
    }
  EXPECT_LT(worst, 0.01);
  const double lampLuminance = 179.0 * (0.2126 * 2 + 0.7152 * 1 + 0.0722 * 0.5);   // 210.6 cd/m^2
  EXPECT_NEAR(luminance.rgb[3 * pixelAt(1.3, 1.3)], lampLuminance, 1e-4 * lampLuminance);

  const LinearImage picture = readImage((dir_ / "luminance.falsecolor.png").string());
  EXPECT_EQ(picture.width, uint32_t(kSize + 16 + 150));   // the image, a margin, the legend
  const FalseColorScale scale{.maximum = 100, .steps = 8, .unit = "cd/m2"};
  const auto byte = [&](size_t pixel, int channel) { return int(std::lround(picture.rgb[3 * pixel + channel] * 255)); };
  for (const size_t p : {pixelAt(0, 0), pixelAt(-1, 1), pixelAt(1.3, 1.3), pixelAt(-1.8, -1.8)}) {
    const size_t at = (p / kSize) * picture.width + p % kSize;
    const Rgb8 expected = scale.colorOf(luminance.rgb[3 * p]);
    for (int c = 0; c < 3; ++c) EXPECT_EQ(byte(at, c), expected[c]) << "pixel " << p << " channel " << c;
  }
  // The legend's bar: red at its top (100+ cd/m^2), dark violet at its foot.
  const size_t barX = kSize + 16 + 5, barTop = 16 + 7 * 2 + 12, barFoot = barTop + 8 * 40;
  EXPECT_EQ(byte(barTop * picture.width + barX, 0), 230);
  EXPECT_EQ(byte(barTop * picture.width + barX, 1), 0);
  EXPECT_EQ(byte(barFoot * picture.width + barX, 0), 40);
  EXPECT_EQ(byte(barFoot * picture.width + barX, 2), 90);
  const auto statistics = nlohmann::json::parse(readFile(dir_ / "luminance.exr.json"));
  EXPECT_EQ(statistics["settings"]["aov"], "luminance");
  EXPECT_EQ(statistics["luminance"]["falsecolor"]["maximum"], 100.0);

  // A PNG cannot hold cd/m^2: refused before anything runs, in one line.
  const fs::path png = dir_ / "luminance.png";
  EXPECT_NE(runCommand({kBin + "portico", "render", store.string(), "-o", png.string(), "--aov", "luminance"},
                       dir_ / "png.log"),
            0);
  EXPECT_NE(readFile(dir_ / "png.log").find("--aov luminance writes cd/m^2 as floats"), std::string::npos)
      << readFile(dir_ / "png.log");
  EXPECT_FALSE(fs::exists(png));
}

// A camera sees an IES luminaire's luminous opening (building.json
// "opening", over the file's 0 0 0) with the luminance I(gamma, C) /
// A_projected: through `portico render` on one cell, and on a 2 x 2 x 2 grid
// of cells where the opening straddles four of them (a camera ray finds it
// in whichever cell its line meets it, the camera in another), the pixels
// wholly on the opening are within 1 % of the closed form (a rectangle:
// L W cos gamma), 5 % more light fails; one and two workers give the same
// bits; the file's own opening (a point) leaves those pixels dark.
TEST_F(PhotometricLights, ACameraSeesTheLuminousOpeningAtIOverItsProjectedAreaInAnyCellWithTheSameBits) {
  writeIes(dir_ / "downlight.ies");
  writeFloor(dir_ / "floor.obj", 3);
  constexpr int kSize = 40;
  const Vec3 luminaire(0, kHeight, 0), eye(1.5f, 0.6f, 1.2f);
  nlohmann::json building = {
      {"objects", {{{"obj", "floor.obj"}, {"albedo", {kAlbedo, kAlbedo, kAlbedo}}}}},
      // 0.3 m wide (along C90: z), 0.6 m long (along C0: x), flat, facing down.
      {"lights",
       {{{"name", "panel"}, {"ies", "downlight.ies"}, {"position", {0, kHeight, 0}}, {"colour", {1, 1, 1}},
         {"opening", {0.3, 0.6, 0}}}}},
      {"camera",
       {{"origin", {eye.x, eye.y, eye.z}}, {"target", {0, kHeight, 0}}, {"up", {0, 1, 0}}, {"fov_y_deg", 20},
        {"width", kSize}, {"height", kSize}}}};
  const fs::path oneCell = import("opening", building);
  const fs::path store = dir_ / "opening-grid-store";
  ASSERT_EQ(runCommand({kBin + "portico", "scene", "import", "--grid", "2", (dir_ / "opening.json").string(),
                        store.string()},
                       dir_ / "grid-import.log"),
            0)
      << readFile(dir_ / "grid-import.log");
  const SceneStore grid = SceneStore::open(store.string());
  ASSERT_EQ(grid.cells().size(), 8u);
  int cellsReached = 0;   // the cells the opening reaches into
  for (const CellInfo& cell : grid.cells())
    cellsReached += cell.bounds.lo.x < 0.3f && cell.bounds.hi.x > -0.3f && cell.bounds.lo.z < 0.15f &&
                    cell.bounds.hi.z > -0.15f && cell.bounds.lo.y <= kHeight && cell.bounds.hi.y >= kHeight;
  EXPECT_EQ(cellsReached, 4);
  const std::vector<std::string> options{"--spp", "4"};   // render() adds 1 worker, 20 000 photons
  const LinearImage single = render(oneCell, "one-cell", options);
  const LinearImage gridOne = render(store, "grid-1", options);
  std::vector<std::string> twoWorkers{kBin + "portico", "render", store.string(), "-o", (dir_ / "grid-2.exr").string(),
                                      "--workers", "2", "--spp", "4", "--photons", "20000"};
  ASSERT_EQ(runCommand(twoWorkers, dir_ / "grid-2.log"), 0) << readFile(dir_ / "grid-2.log");
  const LinearImage gridTwo = readImage((dir_ / "grid-2.exr").string());
  EXPECT_TRUE(gridOne.rgb == gridTwo.rgb) << "one and two workers render different bits";

  // The pixels whose four corners' rays all meet the opening's rectangle.
  const Vec3 forward = normalize(luminaire - eye);
  const Vec3 right = normalize(cross(forward, Vec3(0, 1, 0))), up = cross(right, forward);
  const float tanHalf = std::tan(10.0f * float(kDeg));
  const auto through = [&](float px, float py) {
    return normalize(forward + right * ((2 * px / kSize - 1) * tanHalf) + up * ((1 - 2 * py / kSize) * tanHalf));
  };
  const auto onOpening = [&](const Vec3& d) {
    const Vec3 p = eye + d * ((kHeight - eye.y) / d.y) - luminaire;
    return std::abs(p.x) < 0.3f && std::abs(p.z) < 0.15f;
  };
  const auto luminanceOf = [&](const LinearImage& image, size_t pixel) {
    return 179.0 * (0.2126 * image.rgb[3 * pixel] + 0.7152 * image.rgb[3 * pixel + 1] + 0.0722 * image.rgb[3 * pixel + 2]);
  };
  building["lights"][0].erase("opening");
  const LinearImage unseen = render(import("point", building), "point", options);
  for (const auto& [image, what] : {std::pair<const LinearImage&, const char*>{single, "one cell"}, {gridOne, "8 cells"}}) {
    double worst = 0, nearestWrong = 1e9;
    int covered = 0;
    for (int y = 0; y < kSize; ++y)
      for (int x = 0; x < kSize; ++x) {
        if (!(onOpening(through(x, y)) && onOpening(through(x + 1, y)) && onOpening(through(x, y + 1)) &&
              onOpening(through(x + 1, y + 1))))
          continue;
        ++covered;
        const Vec3 toward = -through(x + 0.5f, y + 0.5f);   // from the luminaire; its frame: C0 +x, C90 -z, nadir -y
        const double gamma = std::acos(double(-toward.y)) / kDeg;
        double c = std::atan2(double(-toward.z), double(toward.x)) / kDeg;
        if (c < 0) c += 360;
        const double expected = candela(gamma, c) / (0.6 * 0.3 * double(-toward.y));
        const size_t pixel = size_t(y) * kSize + x;
        worst = std::max(worst, std::abs(luminanceOf(image, pixel) / expected - 1));
        nearestWrong = std::min(nearestWrong, std::abs(luminanceOf(image, pixel) / (1.05 * expected) - 1));
        EXPECT_LT(luminanceOf(unseen, pixel), 1.0) << "a point luminaire shows at pixel " << pixel;
      }
    std::printf("  %s: %d pixels wholly on the opening, worst %.3f %% from I / (L W cos gamma); against 5 %% more "
                "light at least %.3f %%\n",
                what, covered, 100 * worst, 100 * nearestWrong);
    EXPECT_GT(covered, 100) << what;
    EXPECT_LT(worst, 0.01) << what;
    EXPECT_GT(nearestWrong, 0.01) << what;
  }
}

// A lamp given by its flux renders exactly as the lamp given by the
// radiance that flux makes: the same bits.
TEST_F(PhotometricLights, LumensRenderTheSameBitsAsTheRadianceTheyMake) {
  writeFloor(dir_ / "floor.obj", 3);
  const nlohmann::json quad = {{"corner", {-0.3, 1.5, -0.3}}, {"edge1", {0.6, 0, 0}}, {"edge2", {0, 0, 0.6}}};
  nlohmann::json building = {{"objects", {{{"obj", "floor.obj"}, {"albedo", {0.6, 0.5, 0.4}}}}},
                             {"lights", {{{"name", "panel"}, {"quad", quad}, {"lumens", 1000}, {"colour_temperature", 3000}}}},
                             {"camera", camera(32)}};
  const fs::path byLumens = import("lumens", building);
  const SceneStore lumensStore = SceneStore::open(byLumens.string());
  ASSERT_EQ(lumensStore.lights().size(), 1u);
  const Vec3 radiance = lumensStore.lights()[0].radiance;
  // 1000 lm out: 179 lm/W x Y(pi A L).
  EXPECT_NEAR(lumensOfPower(lumensStore.lights()[0].power()), 1000.0, 1e-3);
  EXPECT_EQ(radiance, radianceOfLumens(1000, colourOfTemperature(3000), 0.36f));
  char text[128];
  std::snprintf(text, sizeof text, "[%.9g, %.9g, %.9g]", radiance.x, radiance.y, radiance.z);
  building["lights"][0].erase("lumens");
  building["lights"][0].erase("colour_temperature");
  building["lights"][0]["radiance"] = nlohmann::json::parse(text);
  const fs::path byRadiance = import("radiance", building);
  EXPECT_EQ(SceneStore::open(byRadiance.string()).lights()[0].radiance, radiance);
  const LinearImage a = render(byLumens, "lumens", {"--spp", "4"}), b = render(byRadiance, "radiance", {"--spp", "4"});
  ASSERT_EQ(a.rgb.size(), b.rgb.size());
  EXPECT_TRUE(a.rgb == b.rgb) << "the two lamps render different images";
  double sum = 0;
  for (float v : a.rgb) sum += v;
  EXPECT_GT(sum, 0);
}

}  // namespace
}  // namespace portico
