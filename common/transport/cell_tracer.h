// Traces one ray through one cell: the nearest of the cell's geometry (via
// its accelerator) and the portals it may leave through.
#pragma once

#include <cstdint>
#include <vector>

#include "common/accel/accelerator.h"
#include "common/scene/store/cell_geometry.h"
#include "common/transport/cell_portals.h"

namespace portico {

class CellTracer {
 public:
  CellTracer(const CellGeometry& cell, const Accelerator& accelerator);
  // Geometry wins ties with a portal: a wall flush with a portal's edge is hit.
  CellEvent trace(const Ray& ray) const;
  const CellGeometry& cell() const { return cell_; }
  // Neighbour cells whose shared portal lies within `radius` of p (each once).
  void neighborsNear(const Vec3& p, float radius, std::vector<uint32_t>& neighbors) const;

 private:
  const CellGeometry& cell_;
  const Accelerator& accelerator_;
  CellPortals portals_;
};

}  // namespace portico
