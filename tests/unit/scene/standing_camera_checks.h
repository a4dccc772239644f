// What a generated building's standing camera must be: its eye inside its
// cell at standing height, clear of every triangle of the cell (not inside
// furniture, not against a wall), looking across the cell at something at
// least 2 m away within it.
#pragma once

#include <gtest/gtest.h>

#include <cmath>

#include "common/scene/generator/standing_camera.h"
#include "common/scene/store/cell_geometry.h"
#include "common/scene/store/scene_store.h"

namespace portico::testing_support {

inline void expectStandingCameraInItsCell(const SceneStore& store, const Camera& camera) {
  SCOPED_TRACE("camera '" + camera.name + "'");
  ASSERT_LT(camera.cell, store.cells().size());
  const CellInfo& cell = store.cells()[camera.cell];
  EXPECT_TRUE(cell.bounds.contains(camera.origin)) << "eye outside its cell " << cell.name;
  EXPECT_FLOAT_EQ(camera.origin.y - cell.bounds.lo.y, kStandingEyeHeight);
  EXPECT_EQ(store.locateCell(camera.origin), camera.cell) << "another cell holds the eye";
  // The point looked at lies in the same cell, across it.
  const Vec3 look = camera.target - camera.origin;
  EXPECT_GE(std::hypot(look.x, look.z), 2.0f);
  EXPECT_TRUE(cell.bounds.contains(camera.target)) << "looks out of " << cell.name;
  // No triangle's box, grown by 0.25 m, holds the eye.
  const auto geometry = CellGeometry::load(store.cellPath(cell.id), cell.id, store.materials().size());
  const MeshView& mesh = geometry->mesh();
  for (uint32_t t = 0; t < mesh.triangleCount; ++t) {
    Vec3 a, b, c;
    mesh.triangle(t, a, b, c);
    const Bounds3 grown(min(min(a, b), c) - Vec3(0.25f), max(max(a, b), c) + Vec3(0.25f));
    ASSERT_FALSE(grown.contains(camera.origin)) << "triangle " << t << " of " << cell.name << " is within 0.25 m of the eye";
  }
}

}  // namespace portico::testing_support
