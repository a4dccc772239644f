// The portals of one cell as rays meet them: which portal a ray leaves the
// cell by, and which neighbours lie near a point. A cell's tracer uses it
// beside the cell's geometry; daylight follows rays through outdoor cells
// that hold no geometry with it alone (outdoor_passage.h).
#pragma once

#include <cstdint>
#include <vector>

#include "common/math.h"
#include "common/ray.h"
#include "common/scene/store/cell_geometry.h"

namespace portico {

struct CellEvent {
  enum class Kind { Surface, Portal, Leave } kind = Kind::Leave;
  float t = kInfinity;
  uint32_t primitive = kNoPrimitive;    // Surface
  float u = 0, v = 0;                   // Surface: barycentrics of vertices 1 and 2
  uint32_t neighborCell = 0;            // Portal
};

class CellPortals {
 public:
  // cellCenter decides each portal's outward side: cells are convex, so
  // the outside of a portal is the side away from the centre.
  CellPortals(const std::vector<CellPortalView>& portals, const Vec3& cellCenter);
  // `event` holds the nearest geometry along `ray` (Surface) or nothing
  // (Leave); it becomes a Portal event when the ray leaves through a
  // portal strictly nearer. A ray leaves only through portals it moves
  // out of.
  void leaveBy(const Ray& ray, CellEvent& event) const;
  // Neighbour cells whose shared portal lies within `radius` of p (each once).
  void neighborsNear(const Vec3& p, float radius, std::vector<uint32_t>& neighbors) const;
  bool empty() const { return triangles_.empty(); }

 private:
  struct PortalTriangle {
    Vec3 v0, v1, v2;
    Vec3 outward;            // unit normal pointing out of this cell
    uint32_t neighborCell;
    // The triangle's box, grown by far more than the triangle test's
    // rounding: a ray segment whose box misses it cannot hit the triangle
    // (cell_portals.cpp), so most rays skip the exact test.
    Bounds3 reach;
  };
  struct PortalPolygon {
    std::vector<Vec3> points;
    Vec3 normal;
    uint32_t neighborCell;
    Bounds3 bounds;   // of the points: a cheap rejection before the exact distance
  };
  std::vector<PortalTriangle> triangles_;
  std::vector<PortalPolygon> polygons_;
};

// Where a ray that crosses a portal at distance t restarts in the
// neighbour: the same ray (origin and direction) from just before the
// portal. Restarting from the rounded crossing point instead would put a
// surface lying on the portal's plane, or a hair beyond it, at a slightly
// negative distance, and the ray would pass through it. Going back 2^-16 of
// the coordinates' magnitude covers the rounding of both hit distances; the
// neighbour holds nothing the ray has already passed, so nothing is hit
// twice, and it ignores the portal the ray came through: rays leave only
// through outward portals.
float tMinBeforePortal(const Ray& ray, float t);

}  // namespace portico
