#include "common/transport/cell_tracer.h"

namespace portico {

CellTracer::CellTracer(const CellGeometry& cell, const Accelerator& accelerator)
    : cell_(cell), accelerator_(accelerator), portals_(cell.portals(), cell.bounds().center()) {}

void CellTracer::neighborsNear(const Vec3& p, float radius, std::vector<uint32_t>& neighbors) const {
  portals_.neighborsNear(p, radius, neighbors);
}

CellEvent CellTracer::trace(const Ray& ray) const {
  CellEvent event;
  const Hit hit = accelerator_.intersect(ray);
  if (hit.found()) {
    event.kind = CellEvent::Kind::Surface;
    event.t = hit.t;
    event.primitive = hit.primitive;
    event.u = hit.u;
    event.v = hit.v;
    // The hit point and normal come from the mesh's vertices next
    // (interiorHitPoint): start their cache misses now, beside the portal
    // tests, rather than after them.
    const MeshView& mesh = cell_.mesh();
    const uint32_t* corners = mesh.indices + 3 * size_t(hit.primitive);
    __builtin_prefetch(mesh.positions + 3 * size_t(corners[0]));
    __builtin_prefetch(mesh.positions + 3 * size_t(corners[1]));
    __builtin_prefetch(mesh.positions + 3 * size_t(corners[2]));
  }
  portals_.leaveBy(ray, event);
  return event;
}

}  // namespace portico
