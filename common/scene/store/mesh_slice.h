// Where a cell's triangles cross a horizontal plane, seen from above: the
// walls `portico scene plan` draws and the walls a work-plane grid keeps
// its distance from.
#pragma once

#include <vector>

#include "common/mesh_view.h"

namespace portico {

// A segment in plan (x-z).
struct PlanSegment {
  float x0, z0, x1, z1;
};

// Appends to `segments` where the triangles of `mesh` cross the plane
// y = height. Triangles lying in the plane (floors, ceilings) give none.
void sliceMesh(const MeshView& mesh, float height, std::vector<PlanSegment>& segments);

}  // namespace portico
