// What `portico scene plan` draws as walls: the cells' triangles cut by a
// horizontal plane at eye height above each floor, as x-z segments.
#pragma once

#include <cstdint>
#include <vector>

#include "common/scene/store/mesh_slice.h"
#include "common/scene/store/scene_store.h"

namespace portico::cli {

// The segments where the triangles of `cells` cross the plane y = height.
// Triangles lying in the plane (floors, ceilings) give none.
std::vector<PlanSegment> sliceCells(const SceneStore& store, const std::vector<uint32_t>& cells, float height);

}  // namespace portico::cli
