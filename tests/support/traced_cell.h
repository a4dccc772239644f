// A store's cell ready to trace, as a worker holds it: the store, the cell's
// geometry, a BVH over it and the tracer that meets geometry and portals.
// Kernel tests that shade one cell of a small store build exactly this.
#pragma once

#include <filesystem>
#include <memory>

#include "common/accel/accelerator.h"
#include "common/scene/store/cell_geometry.h"
#include "common/scene/store/scene_store.h"
#include "common/transport/cell_tracer.h"

namespace portico::testing_support {

struct TracedCell {
  explicit TracedCell(const std::filesystem::path& storeDirectory, uint32_t cellIndex = 0)
      : store(SceneStore::open(storeDirectory)),
        cell(CellGeometry::load(store.cellPath(cellIndex), cellIndex, store.materials().size())),
        accelerator(buildAccelerator(parseAcceleratorSpec("bvh"), cell->mesh())),
        tracer(*cell, *accelerator) {}

  const SceneStore store;
  const std::unique_ptr<CellGeometry> cell;
  const std::unique_ptr<Accelerator> accelerator;
  const CellTracer tracer;   // refers to *cell and *accelerator: declared after them
};

}  // namespace portico::testing_support
