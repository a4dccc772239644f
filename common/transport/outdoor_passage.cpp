#include "common/transport/outdoor_passage.h"

#include <algorithm>

#include "common/transport/daylight_openings.h"

namespace portico {

namespace {
// Beyond where `ray` leaves `box` grown by a millimetre and a thousandth
// of its size: its portals lie on its faces, so none is further. A bounded
// segment lets the portal test skip the portals it cannot reach (a sky
// cell has one over every top-floor room).
float pastBox(const Ray& ray, const Bounds3& box) {
  const Vec3 size = box.hi - box.lo;
  const float margin = 1e-3f + 1e-3f * std::max(size.x, std::max(size.y, size.z));
  float exit = kInfinity;
  for (int axis = 0; axis < 3; ++axis) {
    const float d = ray.direction[axis];
    if (d == 0.0f) continue;
    const float face = d > 0 ? box.hi[axis] + margin : box.lo[axis] - margin;
    exit = std::min(exit, (face - ray.origin[axis]) / d);
  }
  return exit * 1.001f + margin;
}
}  // namespace

OutdoorPassage::OutdoorPassage(const SceneStore& scene) {
  const auto& cells = scene.cells();
  outdoor_.resize(cells.size());
  std::unordered_map<uint32_t, std::vector<CellPortalView>> portalsOfEmpty;
  for (size_t c = 0; c < cells.size(); ++c) {
    outdoor_[c] = isOutdoorCell(cells[c].name);
    if (!outdoor_[c]) continue;
    if (cells[c].triangleCount == 0) portalsOfEmpty[static_cast<uint32_t>(c)];
  }
  if (portalsOfEmpty.empty()) return;
  for (const Portal& portal : scene.portals()) {
    if (auto a = portalsOfEmpty.find(portal.cellA); a != portalsOfEmpty.end())
      a->second.push_back({portal.id, portal.cellB, portal.polygon});
    if (auto b = portalsOfEmpty.find(portal.cellB); b != portalsOfEmpty.end())
      b->second.push_back({portal.id, portal.cellA, portal.polygon});
  }
  for (auto& [cell, portals] : portalsOfEmpty)
    emptyOutdoorCells_.emplace(cell, EmptyCell{CellPortals(portals, cells[cell].bounds.center()), cells[cell].bounds});
}

OutdoorPassage::End OutdoorPassage::follow(Ray ray, uint32_t cell) const {
  // Rays leave convex cells outwards only, so they cannot circle; the
  // bound guards against a malformed store.
  constexpr int kMaxCells = 1024;
  for (int step = 0; step < kMaxCells; ++step) {
    const auto empty = emptyOutdoorCells_.find(cell);
    if (empty == emptyOutdoorCells_.end()) return {false, cell, ray.tMin};
    ray.tMax = pastBox(ray, empty->second.bounds);
    CellEvent event;
    if (ray.tMax > ray.tMin) empty->second.portals.leaveBy(ray, event);
    if (event.kind != CellEvent::Kind::Portal) return {true, 0, 0};
    ray.tMin = tMinBeforePortal(ray, event.t);
    cell = event.neighborCell;
  }
  return {false, cell, ray.tMin};
}

}  // namespace portico
