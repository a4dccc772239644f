// A furnished cell of a chosen triangle count, for benchmarks and tests of
// the accelerators: an open-plan hall (floor, ceiling, four walls: 12
// triangles) filled with the demo building's furniture (demo_furniture.h),
// zone after zone, each furniture triangle tessellated into k x k smaller
// ones. The triangles come from furniture, not from subdivided walls: the
// hall grows slowly (about sqrt(n) / 10 zones of 4 m x 4.5 m) and the
// tessellation does the rest, so large cells are dense, as finely modelled
// rooms are. The last piece is cut short so the count is exactly `triangles`.
// The same (triangles, seed) gives the same bytes.
#pragma once

#include <cstddef>
#include <cstdint>

#include "common/math.h"
#include "common/scene/store/scene_store.h"

namespace portico {

struct FurnishedHall {
  CellContent cell;      // positions, indices, materials (bounds = the hall's box)
  Vec3 eye;              // a point in the air above the furniture, mid-hall
  int tessellation = 1;  // k: each furniture triangle became k * k
  uint32_t zones = 0;    // furnished zones (one room's worth of furniture each)
};

// At least 12 triangles (the hall's shell alone).
FurnishedHall generateFurnishedHall(size_t triangles, uint64_t seed);

}  // namespace portico
