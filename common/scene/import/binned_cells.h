// Writes an imported scene's triangles into cells that the scene's own cells
// do not describe (voxel cells, found rooms): every triangle goes into every
// cell it touches, binned in two passes (count, then fill one flat reference
// array) so that each cell is assembled and written on its own while only
// the input meshes and one output cell are held in full.
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "common/scene/import/imported_scene.h"
#include "common/scene/store/scene_store.h"

namespace portico {

// Calls `visit(cell)` once for each cell triangle `triangle` of `object` touches.
using TouchedCells =
    std::function<void(const ImportedObject& object, size_t triangle, const std::function<void(uint32_t)>& visit)>;

// Writes cells 0 .. cellCount - 1, named and bounded by `name` and `bounds`,
// each with the triangles `touched` puts in it, in input order.
void writeBinnedCells(const ImportedScene& scene, uint32_t cellCount, const TouchedCells& touched,
                      const std::function<std::string(uint32_t)>& name,
                      const std::function<Bounds3(uint32_t)>& bounds, SceneStoreWriter& writer);

}  // namespace portico
