// EmitterPixels against rays: a pixel it leaves unmarked is one where no
// camera ray through any point of the pixel meets an emitter of the cell
// (tested at a grid of points over every pixel, with a brute-force
// intersector), so skipping its emission rays changes nothing.
#include "common/transport/emitter_pixels.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "common/accel/brute_force.h"
#include "common/scene/import/building_importer.h"
#include "common/scene/store/cell_geometry.h"
#include "common/scene/store/scene_store.h"
#include "tests/support/temp_directory.h"

namespace portico {
namespace {

namespace fs = std::filesystem;

TEST(EmitterPixels, AnUnmarkedPixelShowsNoEmitterAnywhereInIt) {
  const fs::path storePath = testing_support::tempPath("emitter-pixels", false);
  importBuilding({std::string(PORTICO_REFERENCE_DIR) + "/cornell_closed/scene.json"}, storePath.string(), ImportOptions{});
  const SceneStore store = SceneStore::open(storePath.string());
  const Camera& camera = store.camera();
  const uint32_t cellId = camera.cell;
  const auto cell = CellGeometry::load(store.cellPath(cellId), cellId, store.materials().size());
  const BruteForce brute(cell->mesh());
  // A small image: every pixel is tested.
  const uint32_t width = 48, height = 48;
  const CameraModel model(camera, width, height);
  const EmitterPixels pixels(model, width, height, *cell, store.materials());
  uint64_t emitterHits = 0;
  for (uint32_t pixel = 0; pixel < width * height; ++pixel) {
    const uint32_t x = pixel % width, y = pixel / width;
    bool seesEmitter = false;
    for (uint32_t i = 0; i <= 8; ++i)
      for (uint32_t j = 0; j <= 8; ++j) {
        const Ray ray{model.origin(), model.direction(float(x) + float(i) / 8.0f, float(y) + float(j) / 8.0f), 0.0f,
                      kInfinity};
        const Hit hit = brute.intersect(ray);
        if (hit.found() && store.materials()[cell->material(hit.primitive)].emissive()) seesEmitter = true;
      }
    emitterHits += seesEmitter;
    if (seesEmitter) EXPECT_TRUE(pixels.mayShowEmitter(pixel)) << "pixel " << x << ", " << y;
  }
  // The lamp shows, and the marked pixels are few: its box and a margin.
  EXPECT_GT(emitterHits, 0u);
  EXPECT_GE(pixels.markedCount(), emitterHits);
  EXPECT_LT(pixels.markedCount(), uint64_t{width} * height / 10);
  fs::remove_all(storePath);
}

}  // namespace
}  // namespace portico
