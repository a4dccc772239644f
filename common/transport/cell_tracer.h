// Traces one ray through one cell: the nearest of the cell's geometry (via
// its accelerator) and the portals it may leave through.
#pragma once

#include <cstdint>
#include <vector>

#include "common/accel/accelerator.h"
#include "common/scene/store/cell_geometry.h"

namespace portico {

struct CellEvent {
  enum class Kind { Surface, Portal, Leave } kind = Kind::Leave;
  float t = kInfinity;
  uint32_t primitive = kNoPrimitive;    // Surface
  float u = 0, v = 0;                   // Surface: barycentrics of vertices 1 and 2
  uint32_t neighborCell = 0;            // Portal
};

class CellTracer {
 public:
  CellTracer(const CellGeometry& cell, const Accelerator& accelerator);
  // Geometry wins ties with a portal: a wall flush with a portal's edge is hit.
  CellEvent trace(const Ray& ray) const;
  const CellGeometry& cell() const { return cell_; }
  // Neighbour cells whose shared portal lies within `radius` of p (each once).
  void neighborsNear(const Vec3& p, float radius, std::vector<uint32_t>& neighbors) const;

 private:
  struct PortalTriangle {
    Vec3 v0, v1, v2;
    Vec3 outward;            // unit normal pointing out of this cell
    uint32_t neighborCell;
    // The triangle's box, grown by far more than the triangle test's
    // rounding: a ray segment whose box misses it cannot hit the triangle
    // (cell_tracer.cpp), so most rays skip the exact test.
    Bounds3 reach;
  };
  struct PortalPolygon {
    std::vector<Vec3> points;
    Vec3 normal;
    uint32_t neighborCell;
    Bounds3 bounds;   // of the points: a cheap rejection before the exact distance
  };
  const CellGeometry& cell_;
  const Accelerator& accelerator_;
  std::vector<PortalTriangle> portalTriangles_;
  std::vector<PortalPolygon> portalPolygons_;
};

}  // namespace portico
