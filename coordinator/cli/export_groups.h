// How `portico scene export` groups a cell's triangles, for every format:
// one group per material, except emissive triangles, where each lamp (two
// consecutive triangles forming a parallelogram, else one triangle) is a
// group of its own, so that `portico scene import` of the exported file
// reads each back as one light (a quad or a triangle light).
#pragma once

#include <cstdint>
#include <vector>

#include "common/scene/store/cell_geometry.h"
#include "common/scene/store/scene_types.h"

namespace portico::cli {

struct TriangleGroup {
  uint32_t material = 0;
  std::vector<uint32_t> triangles;   // of the cell's mesh
  bool lamp = false;
};

// Non-emissive groups first, by material id, then the lamps in mesh order.
std::vector<TriangleGroup> exportGroups(const CellGeometry& geometry, const std::vector<Material>& materials);

}  // namespace portico::cli
