#include "coordinator/cli/plan_walls.h"

#include <memory>

#include "common/scene/store/cell_geometry.h"

namespace portico::cli {

std::vector<PlanSegment> sliceCells(const SceneStore& store, const std::vector<uint32_t>& cells, float height) {
  std::vector<PlanSegment> segments;
  for (uint32_t id : cells) {
    const std::unique_ptr<CellGeometry> cell = CellGeometry::load(store.cellPath(id), id, store.materials().size());
    sliceMesh(cell->mesh(), height, segments);
  }
  return segments;
}

}  // namespace portico::cli
