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
  }
  portals_.leaveBy(ray, event);
  return event;
}

}  // namespace portico
