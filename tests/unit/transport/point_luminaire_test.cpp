// A point luminaire's photons (emitPhoton): they start at its point, carry
// together exactly its flux, and their directions, turned into the
// luminaire's frame (aimed and rotated in the scene), follow its candela
// distribution. And its direct light, through a cell kernel's camera rays,
// on a diffuse plane: rho E / pi with E = I cos / d^2.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "common/accel/accelerator.h"
#include "common/photometry/ies_file.h"
#include "common/photometry/lamp_colour.h"
#include "common/scene/store/cell_geometry.h"
#include "common/scene/store/scene_store.h"
#include "common/transport/cell_kernel.h"
#include "common/transport/photon_scattering.h"
#include "tests/support/traced_cell.h"
#include "tests/unit/photometry/ies_test_files.h"
#include "tests/unit/scene/scene_test_support.h"

namespace portico {
namespace {

constexpr double kDeg = M_PI / 180.0;

// Brightest at the nadir, towards C0; smooth, so the file's grid samples it well.
double candela(double gamma, double c) {
  return (200 + 800 * std::pow(std::cos(0.5 * gamma * kDeg), 2)) * (1 + 0.5 * std::cos(c * kDeg));
}

AreaLight luminaire() {
  AreaLight light;
  light.shape = LightShape::Point;
  light.corner = Vec3(1, 2.5f, -3);
  // Aimed obliquely, C0 across the aim.
  light.edge1 = normalize(Vec3(0.3f, -1, 0.2f));
  light.edge2 = normalize(cross(light.edge1, Vec3(0, 0, 1)));
  light.intensity = std::make_shared<const LuminousIntensity>(
      parseIes(ies_test::iesText(ies_test::angles(0, 180, 2.5), ies_test::angles(0, 360, 5), candela), "lamp.ies").grid,
      "lamp.ies");
  light.radiance = powerOfLumens(1, colourOfTemperature(3000));   // W/sr per cd
  return light;
}

TEST(PointLuminaire, PhotonsStartAtItsPointAndCarryItsFluxExactly) {
  const AreaLight light = luminaire();
  constexpr uint64_t kPhotons = 100000;
  const Vec3 power = light.power() / float(kPhotons);
  double sum[3] = {0, 0, 0};
  for (uint64_t path = 0; path < kPhotons; ++path) {
    const RayState photon = emitPhoton(light, light.normal(), power, 11, path);
    ASSERT_EQ(photon.origin, light.corner);
    ASSERT_NEAR(length(photon.direction), 1.0f, 1e-5f);
    for (int c = 0; c < 3; ++c) sum[c] += photon.weight[c];
  }
  // The luminaire's flux: its lumens x the colour per candela; 179 Y = lumens.
  const double lumens = light.intensity->lumens();
  EXPECT_NEAR(lumensOfPower(light.power()), lumens, 1e-4 * lumens);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(sum[c], light.power()[c], 1e-5 * light.power()[c]);
  std::printf("  %llu photons carry %.4f lm of the luminaire's %.4f lm\n", (unsigned long long)kPhotons,
              lumensOfPower(Vec3(float(sum[0]), float(sum[1]), float(sum[2]))), lumens);
}

// Directions in world space, read back in the luminaire's frame, fall in
// zones of 20 x 60 degrees as the closed-form flux of each zone says.
TEST(PointLuminaire, PhotonDirectionsFollowTheCandelaDistributionInItsFrame) {
  const AreaLight light = luminaire();
  constexpr int kRows = 9, kColumns = 6, kPhotons = 300000;
  std::vector<double> counts(kRows * kColumns, 0.0);
  const Vec3 c90 = light.luminaireC90();
  for (uint64_t path = 0; path < kPhotons; ++path) {
    const Vec3 d = emitPhoton(light, light.normal(), Vec3(1), 3, path).direction;
    const double gamma = std::acos(std::clamp(double(dot(d, light.edge1)), -1.0, 1.0)) / kDeg;
    double c = std::atan2(double(dot(d, c90)), double(dot(d, light.edge2))) / kDeg;
    if (c < 0) c += 360;
    counts[std::min(kRows - 1, int(gamma / 20)) * kColumns + std::min(kColumns - 1, int(c / 60))] += 1;
  }
  double total = 0;
  std::vector<double> flux(kRows * kColumns, 0.0);
  constexpr int kSteps = 120;
  for (int zone = 0; zone < kRows * kColumns; ++zone)
    for (int i = 0; i < kSteps; ++i)
      for (int j = 0; j < kSteps; ++j) {
        const double g0 = (zone / kColumns) * 20 + 20.0 * i / kSteps, g1 = g0 + 20.0 / kSteps;
        const double c = (zone % kColumns) * 60 + 60.0 * (j + 0.5) / kSteps;
        const double f = candela(0.5 * (g0 + g1), c) * (std::cos(g0 * kDeg) - std::cos(g1 * kDeg)) * (60.0 / kSteps * kDeg);
        flux[zone] += f;
        total += f;
      }
  for (int zone = 0; zone < kRows * kColumns; ++zone) {
    const double p = flux[zone] / total, expected = p * kPhotons;
    EXPECT_NEAR(counts[zone], expected, 4 * std::sqrt(kPhotons * p * (1 - p)) + 3e-3 * expected + 1)
        << "zone gamma " << (zone / kColumns) * 20 << ", C " << (zone % kColumns) * 60;
  }
}

// Its intensity towards a direction is the file's, turned by its frame: C0
// is edge2, the nadir edge1.
TEST(PointLuminaire, IntensityTowardReadsTheDistributionInItsFrame) {
  const AreaLight light = luminaire();
  const Vec3 perCandela = light.radiance;
  const auto candelaToward = [&](const Vec3& d) { return light.intensityToward(normalize(d)).y / perCandela.y; };
  // 60 degrees from the nadir towards C0, and towards C180.
  const Vec3 towardC0 = light.edge1 * 0.5f + light.edge2 * float(std::sqrt(0.75));
  const Vec3 towardC180 = light.edge1 * 0.5f - light.edge2 * float(std::sqrt(0.75));
  EXPECT_NEAR(candelaToward(towardC0), candela(60, 0), 10.0);
  EXPECT_NEAR(candelaToward(towardC180), candela(60, 180), 10.0);
  // 150 degrees from the nadir towards C90.
  EXPECT_NEAR(candelaToward(light.edge1 * float(std::cos(150 * kDeg)) + light.luminaireC90() * 0.5f),
              candela(150, 90), 10.0);
}

// A downlight brighter towards C0 (+x) away from the nadir (smoothly: the
// same all round at the nadir), dark above the horizontal.
double downlight(double gamma, double c) {
  return gamma > 90 ? 0.0 : (500 + 1000 * std::cos(gamma * kDeg)) * (1 + 0.3 * std::sin(gamma * kDeg) * std::cos(c * kDeg));
}

// A store of one cell: a 100 x 100 m floor (albedo 0.5) at y = 0 under the
// downlight at 2 m, aimed down with C0 along +x; the camera 1.9 m up looking
// straight down (90 degrees, +x to the right, +z down the image).
void writePlaneUnderDownlight(const std::string& directory, uint32_t size) {
  SceneStoreWriter writer(directory);
  writer.addMaterial("floor", Vec3(0.5f));
  AreaLight light;
  light.shape = LightShape::Point;
  light.corner = Vec3(0, 2, 0);
  light.edge1 = Vec3(0, -1, 0);
  light.edge2 = Vec3(1, 0, 0);
  light.intensity = std::make_shared<const LuminousIntensity>(
      parseIes(ies_test::iesText(ies_test::angles(0, 90, 2.5), ies_test::angles(0, 360, 5), downlight), "d.ies").grid,
      "d.ies");
  light.radiance = Vec3(1.0f / 179.0f);   // white: Y = 1 per 179 lm/W
  writer.addLight(light);
  Camera camera;
  camera.origin = Vec3(0, 1.9f, 0);
  camera.target = Vec3(0, 0, 0);
  camera.up = Vec3(0, 0, -1);
  camera.fovYDegrees = 90;
  camera.width = camera.height = size;
  writer.setCamera(camera);
  CellContent cell;
  cell.name = "floor";
  cell.bounds = Bounds3(Vec3(-50, -0.01f, -50), Vec3(50, 2.1f, 50));
  cell.positions = {-50, 0, -50, -50, 0, 50, 50, 0, 50, 50, 0, -50};
  cell.indices = {0, 1, 2, 0, 2, 3};   // facing +y
  cell.materials = {0, 0};
  writer.writeCell(cell);
  writer.commit();
}

TEST(PointLuminaire, ACellKernelLightsAPlaneByTheInverseSquareAndCosineLaws) {
  testing_support::TempDirectory temp;
  constexpr uint32_t kSize = 24;
  writePlaneUnderDownlight(temp / "store", kSize);
  const testing_support::TracedCell traced(temp / "store");
  JobSettings settings;
  settings.width = settings.height = kSize;
  // Enough samples that a pixel's mean is its centre's value (E varies by
  // some 4 % across a pixel at 45 degrees).
  settings.spp = 64;
  CellKernel kernel(traced.store, traced.tracer, settings, nullptr);   // direct light only: no photon map
  KernelOutputs out;
  kernel.generateCameraRays(0, kSize * kSize, out);
  kernel.finishGathers(out);
  double worst = 0, nearestWrong = 1e9;
  for (uint32_t row = 0; row < kSize; ++row)
    for (uint32_t column = 0; column < kSize; ++column) {
      // The floor point at the pixel's centre, its distance and angles from the lamp.
      const double x = 1.9 * (2.0 * (column + 0.5) / kSize - 1.0), z = 1.9 * (2.0 * (row + 0.5) / kSize - 1.0);
      const double d2 = x * x + z * z + 4.0, cosTheta = 2.0 / std::sqrt(d2);
      const double gamma = std::acos(cosTheta) / kDeg;
      const double c = std::atan2(-z, x) / kDeg;   // C90 = cross(C0, nadir) = -z
      const double expected = 0.5 / M_PI * downlight(gamma, c) / 179.0 * cosTheta / d2;
      const auto it = out.film.sums().find(row * kSize + column);
      ASSERT_NE(it, out.film.sums().end());
      for (int64_t channel : {it->second.r, it->second.g, it->second.b}) {
        const double value = fromFixed(channel);
        worst = std::max(worst, std::abs(value / expected - 1));
        nearestWrong = std::min(nearestWrong, std::abs(value / (1.05 * expected) - 1));
      }
    }
  std::printf("  %u pixels: worst error %.3f %% against rho I cos / (pi d^2); against 5 %% more light, at least %.3f %%\n",
              kSize * kSize, 100 * worst, 100 * nearestWrong);
  EXPECT_LT(worst, 0.01);
  EXPECT_GT(nearestWrong, 0.01);   // a 5 % error in the light would fail
}

}  // namespace
}  // namespace portico
