// CellTracer's portal test against a brute-force reference: every portal
// triangle tested with the watertight test, whatever its box. The tracer
// skips a portal whose grown box the ray's segment misses (cell_tracer.cpp);
// these rays aim at the portals' edges and corners, end on them, start on
// their planes and graze them, where a skip that is not conservative would
// show.
#include "common/transport/cell_tracer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <vector>

#include "common/accel/brute_force.h"
#include "common/accel/triangle_intersect.h"
#include "common/rng.h"
#include "common/scene/store/cell_geometry.h"
#include "common/scene/import/building_importer.h"
#include "common/scene/generator/demo_generator.h"
#include "common/scene/store/scene_store.h"
#include "tests/unit/scene/scene_test_support.h"

namespace portico {
namespace {

using testing_support::TempDirectory;

// The reference: the nearest portal triangle the ray moves out through,
// strictly before the surface hit, with the tracer's slack behind the origin.
CellEvent referenceEvent(const CellGeometry& cell, const Accelerator& accelerator, const Ray& ray) {
  CellEvent event;
  const Hit hit = accelerator.intersect(ray);
  if (hit.found()) {
    event.kind = CellEvent::Kind::Surface;
    event.t = hit.t;
    event.primitive = hit.primitive;
  }
  const WatertightRay frame(ray.direction);
  Ray limited = ray;
  limited.tMax = hit.found() ? hit.t : ray.tMax;
  limited.tMin = std::min(ray.tMin, -1e-4f);
  const Vec3 cellCenter = cell.bounds().center();
  for (const CellPortalView& portal : cell.portals()) {
    Vec3 normal(0), centroid(0);
    for (size_t i = 0; i < portal.polygon.size(); ++i) {
      normal += cross(portal.polygon[i], portal.polygon[(i + 1) % portal.polygon.size()]);
      centroid += portal.polygon[i];
    }
    normal = normalize(normal);
    if (dot(normal, centroid / float(portal.polygon.size()) - cellCenter) < 0) normal = -normal;
    if (dot(ray.direction, normal) <= 0) continue;
    for (size_t i = 1; i + 1 < portal.polygon.size(); ++i) {
      float t, u, v;
      if (intersectTriangle(frame, limited, portal.polygon[0], portal.polygon[i], portal.polygon[i + 1], t, u, v) &&
          t < limited.tMax) {
        limited.tMax = t;
        event.kind = CellEvent::Kind::Portal;
        event.t = t;
        event.primitive = kNoPrimitive;
        event.neighborCell = portal.neighborCell;
      }
    }
  }
  return event;
}

Vec3 lerp(const Vec3& a, const Vec3& b, float s) { return a + (b - a) * s; }

// Traces rays at every cell's portals with the tracer and the reference.
void expectPortalEventsMatchReference(const std::string& storeDirectory) {
  const SceneStore store = SceneStore::open(storeDirectory);
  uint64_t rays = 0, portalEvents = 0;
  for (const CellInfo& info : store.cells()) {
    const auto cell = CellGeometry::load(store.cellPath(info.id), info.id, store.materials().size());
    if (cell->portals().empty()) continue;
    const BruteForce brute(cell->mesh());
    const CellTracer tracer(*cell, brute);
    const Bounds3& box = cell->bounds();
    for (uint32_t i = 0; i < 4000; ++i) {
      const auto random = [&](uint32_t dimension) { return randomUniform(7, RandomStream::Photon, info.id, i, dimension); };
      const CellPortalView& portal = cell->portals()[i % cell->portals().size()];
      // A point on the portal, or on one of its edges or corners, nudged by
      // up to a millimetre (most nudges far below it).
      const Vec3& a = portal.polygon[i % portal.polygon.size()];
      const Vec3& b = portal.polygon[(i + 1) % portal.polygon.size()];
      const Vec3& c = portal.polygon[(i + 2) % portal.polygon.size()];
      Vec3 target = (i / 7) % 3 == 0 ? a : (i / 7) % 3 == 1 ? lerp(a, b, random(0)) : lerp(lerp(a, b, random(0)), c, random(1));
      const float nudge = std::pow(10.0f, -3.0f - 4.0f * random(2));
      target += Vec3(random(3) - 0.5f, random(4) - 0.5f, random(5) - 0.5f) * nudge;
      // From inside the cell, or from a point on the portal's plane.
      Vec3 origin(lerp(box.lo, box.hi, 0.05f).x + random(6) * (box.hi.x - box.lo.x) * 0.9f,
                  lerp(box.lo, box.hi, 0.05f).y + random(7) * (box.hi.y - box.lo.y) * 0.9f,
                  lerp(box.lo, box.hi, 0.05f).z + random(8) * (box.hi.z - box.lo.z) * 0.9f);
      if (i % 11 == 0) origin = lerp(a, c, random(9));
      Vec3 direction = target - origin;
      if (i % 11 == 0) direction = Vec3(random(10) - 0.5f, random(11) - 0.5f, random(12) - 0.5f);
      if (!(length(direction) > 0)) continue;
      Ray ray{origin, direction, 0.0f, kInfinity};
      // Segments ending short of, on, and past the portal.
      const uint32_t variant = i % 4;
      if (variant == 1) ray.tMax = 1.0f;
      if (variant == 2) ray.tMax = std::nextafter(1.0f, 0.0f);
      if (variant == 3) ray.tMax = 1.0f + nudge;
      const CellEvent expected = referenceEvent(*cell, brute, ray);
      const CellEvent got = tracer.trace(ray);
      ++rays;
      portalEvents += expected.kind == CellEvent::Kind::Portal;
      ASSERT_EQ(int(got.kind), int(expected.kind)) << "cell " << info.id << " ray " << i;
      ASSERT_EQ(got.t, expected.t) << "cell " << info.id << " ray " << i;
      ASSERT_EQ(got.primitive, expected.primitive) << "cell " << info.id << " ray " << i;
      ASSERT_EQ(got.neighborCell, expected.neighborCell) << "cell " << info.id << " ray " << i;
    }
  }
  EXPECT_GT(rays, 10000u);
  // Enough of them cross a portal for the comparison to mean something.
  EXPECT_GT(portalEvents, rays / 10) << rays << " rays";
}

// Rooms joined by doors: portals framed by walls, floors and lintels.
TEST(CellTracer, PortalEventsInTheDemoBuildingMatchTestingEveryPortalTriangle) {
  TempDirectory temp;
  generateDemoBuilding(temp / "demo", 3);
  expectPortalEventsMatchReference(temp / "demo");
}

// Voxel cells: portals are whole open faces, whose edges and corners rays
// cross into the cells beside and diagonal to them.
TEST(CellTracer, PortalEventsInVoxelCellsMatchTestingEveryPortalTriangle) {
  TempDirectory temp;
  ImportOptions options;
  options.gridResolution = 3;
  importBuilding({std::string(PORTICO_REFERENCE_DIR) + "/cornell_closed/scene.json"}, temp / "voxels", options);
  expectPortalEventsMatchReference(temp / "voxels");
}

}  // namespace
}  // namespace portico
