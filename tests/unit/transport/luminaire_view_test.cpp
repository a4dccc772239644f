// A camera looking at an IES luminaire sees its luminous opening with the
// luminance I(gamma, C) / A_projected: a cell kernel's pixels wholly inside
// the opening's image hold that, from the closed-form candela function and
// the closed-form projected area (a rectangle L W cos gamma, a sphere
// pi r^2); a luminaire without an opening (0 0 0) stays unseen.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <memory>

#include "common/accel/accelerator.h"
#include "common/photometry/ies_file.h"
#include "common/scene/store/cell_geometry.h"
#include "common/scene/store/scene_store.h"
#include "common/transport/camera_model.h"
#include "common/transport/cell_kernel.h"
#include "tests/support/traced_cell.h"
#include "tests/unit/photometry/ies_test_files.h"
#include "tests/unit/scene/scene_test_support.h"

namespace portico {
namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr uint32_t kSize = 40;
const Vec3 kLuminaire(0, 2.5f, 0);

// Brighter towards C0 away from the nadir, dark above the horizontal.
double downlight(double gamma, double c) {
  return gamma > 90 ? 0.0 : (500 + 1000 * std::cos(gamma * kDeg)) * (1 + 0.3 * std::sin(gamma * kDeg) * std::cos(c * kDeg));
}

Camera viewOfLuminaire() {
  Camera camera;
  camera.origin = Vec3(1.5f, 1.0f, 1.2f);   // 52 degrees from its nadir, towards C320
  camera.target = kLuminaire;
  camera.up = Vec3(0, 1, 0);
  camera.fovYDegrees = 20;
  camera.width = camera.height = kSize;
  return camera;
}

// A cell with a diffuse floor (y = 0) and the downlight at 2.5 m, aimed
// down with C0 along +x (so C90 is -z), its opening `opening` (LM-63's
// width length height).
void writeScene(const std::string& directory, const std::string& opening) {
  SceneStoreWriter writer(directory);
  writer.addMaterial("floor", Vec3(0.5f));
  const IesPhotometry ies = parseIes(
      ies_test::iesText(ies_test::angles(0, 90, 2.5), ies_test::angles(0, 360, 5), downlight, 1.0, 1.0,
                        "IESNA:LM-63-2002", 1.0, opening),
      "d.ies");
  AreaLight light;
  light.shape = LightShape::Point;
  light.corner = kLuminaire;
  light.edge1 = Vec3(0, -1, 0);
  light.edge2 = Vec3(1, 0, 0);
  light.intensity = std::make_shared<const LuminousIntensity>(ies.grid, "d.ies");
  light.opening = ies.opening;
  light.radiance = Vec3(1.0f / 179.0f);   // white: 179 Y = candela
  writer.addLight(light);
  writer.setCamera(viewOfLuminaire());
  CellContent cell;
  cell.name = "room";
  cell.bounds = Bounds3(Vec3(-10, -0.01f, -10), Vec3(10, 3, 10));
  cell.positions = {-10, 0, -10, -10, 0, 10, 10, 0, 10, 10, 0, -10};
  cell.indices = {0, 1, 2, 0, 2, 3};
  cell.materials = {0, 0};
  writer.writeCell(cell);
  writer.commit();
}

struct Render {
  KernelOutputs out;
  double pixel(uint32_t index) const {   // the luminance, 179 Y (cd/m^2)
    const auto it = out.film.sums().find(index);
    if (it == out.film.sums().end()) return 0;
    return 179.0 * (0.2126 * fromFixed(it->second.r) + 0.7152 * fromFixed(it->second.g) +
                    0.0722 * fromFixed(it->second.b));
  }
};

Render render(const std::string& opening) {
  testing_support::TempDirectory temp;
  writeScene(temp / "store", opening);
  const testing_support::TracedCell traced(temp / "store");
  JobSettings settings;
  settings.width = settings.height = kSize;
  settings.spp = 4;
  CellKernel kernel(traced.store, traced.tracer, settings, nullptr);
  Render result;
  kernel.generateCameraRays(0, kSize * kSize, result.out);
  kernel.finishGathers(result.out);
  return result;
}

// Checks every pixel whose four corners' rays all meet the opening
// (`covers`, in closed form) against I / A (`area` of the direction from
// the luminaire, in its frame); returns how many there were.
int checkCoveredPixels(const Render& seen, const std::function<bool(const Vec3&)>& covers,
                       const std::function<double(const Vec3&)>& area, const char* what) {
  const CameraModel camera(viewOfLuminaire(), kSize, kSize);
  double worst = 0, nearestWrong = 1e9;
  int covered = 0;
  for (uint32_t y = 0; y < kSize; ++y)
    for (uint32_t x = 0; x < kSize; ++x) {
      bool inside = true;
      for (const float dx : {0.0f, 1.0f})
        for (const float dy : {0.0f, 1.0f}) inside = inside && covers(camera.direction(float(x) + dx, float(y) + dy));
      if (!inside) continue;
      ++covered;
      // The luminaire's frame: x C0 (+x), y C90 (-z), z the nadir (-y).
      const Vec3 toward = -camera.direction(float(x) + 0.5f, float(y) + 0.5f);
      const Vec3 local(toward.x, -toward.z, -toward.y);
      const double gamma = std::acos(double(local.z)) / kDeg;
      double c = std::atan2(double(local.y), double(local.x)) / kDeg;
      if (c < 0) c += 360;
      const double expected = downlight(gamma, c) / area(local);
      const double value = seen.pixel(y * kSize + x);
      worst = std::max(worst, std::abs(value / expected - 1));
      nearestWrong = std::min(nearestWrong, std::abs(value / (1.05 * expected) - 1));
    }
  std::printf("  %s: %d pixels wholly on the opening: worst %.3f %% from I / A_projected; against 5 %% more light, "
              "at least %.3f %%\n",
              what, covered, 100 * worst, 100 * nearestWrong);
  EXPECT_LT(worst, 0.01) << what;
  EXPECT_GT(nearestWrong, 0.01) << what;   // a 5 % brighter luminaire would fail
  return covered;
}

TEST(LuminaireView, ACameraSeesARectangularOpeningAtIOverItsProjectedArea) {
  // 0.3 m wide (along C90, z), 0.6 m long (along C0, x), flat.
  const Render seen = render("0.3 0.6 0");
  const Vec3 origin = viewOfLuminaire().origin;
  const auto covers = [&](const Vec3& d) {
    const float t = (kLuminaire.y - origin.y) / d.y;   // the opening's plane
    const Vec3 p = origin + d * t - kLuminaire;
    return t > 0 && std::abs(p.x) < 0.3f && std::abs(p.z) < 0.15f;
  };
  const int covered = checkCoveredPixels(seen, covers, [](const Vec3& l) { return 0.6 * 0.3 * std::abs(l.z); },
                                         "rectangle 0.6 x 0.3 m");
  EXPECT_GT(covered, 100);
}

TEST(LuminaireView, ACameraSeesASphericalOpeningAtIOverPiRSquared) {
  const Render seen = render("-0.3 -0.3 -0.3");
  const Vec3 origin = viewOfLuminaire().origin;
  const auto covers = [&](const Vec3& d) {
    const Vec3 toCentre = kLuminaire - origin;
    const Vec3 across = toCentre - d * dot(toCentre, d);
    return length(across) < 0.15f;
  };
  const int covered =
      checkCoveredPixels(seen, covers, [](const Vec3&) { return M_PI * 0.15 * 0.15; }, "sphere 0.3 m");
  EXPECT_GT(covered, 100);
}

TEST(LuminaireView, ALuminaireWithoutAnOpeningStaysUnseen) {
  const Render point = render("0 0 0");
  const Render panel = render("0.3 0.6 0");
  // No emitter in the cell: no emission rays at all; where the panel shows,
  // the point luminaire's image has nothing (the sky is black, no daylight).
  EXPECT_EQ(point.out.counters.emissionRays, 0u);
  EXPECT_GT(panel.out.counters.emissionRays, 0u);
  int shown = 0;
  for (uint32_t p = 0; p < kSize * kSize; ++p) {
    if (panel.pixel(p) > 100) {
      ++shown;
      EXPECT_LT(point.pixel(p), 1.0) << "pixel " << p;
    }
  }
  EXPECT_GT(shown, 100);
}

}  // namespace
}  // namespace portico
