// Portal polygons: shape (planar, convex, not degenerate) and position (on a
// face of each of its cells' boxes).
#include "common/scene/store/portal_geometry.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace portico {

Vec3 newellNormal(const std::vector<Vec3>& polygon) {
  Vec3 normal(0);
  for (size_t i = 0; i < polygon.size(); ++i) {
    const Vec3& a = polygon[i];
    const Vec3& b = polygon[(i + 1) % polygon.size()];
    normal += Vec3((a.y - b.y) * (a.z + b.z), (a.z - b.z) * (a.x + b.x), (a.x - b.x) * (a.y + b.y));
  }
  return normal;
}

std::string portalShapeProblem(const std::vector<Vec3>& polygon) {
  if (polygon.size() < 3) return fmt::format("has {} points; a polygon needs at least 3", polygon.size());
  Bounds3 box;
  for (size_t i = 0; i < polygon.size(); ++i) {
    if (!isFinite(polygon[i]))
      return fmt::format("point {} ({}, {}, {}) is not finite", i, polygon[i].x, polygon[i].y, polygon[i].z);
    box.extend(polygon[i]);
  }
  const float size = maxComponent(box.diagonal());
  const Vec3 newell = newellNormal(polygon);
  if (!(size > 0.0f) || length(newell) <= 1e-8f * size * size) return "has zero area";
  const Vec3 normal = normalize(newell);
  for (size_t i = 0; i < polygon.size(); ++i)
    if (std::abs(dot(polygon[i] - polygon[0], normal)) > 1e-4f * size)
      return fmt::format("is not planar (point {} lies {} m off the plane of the others)", i,
                         std::abs(dot(polygon[i] - polygon[0], normal)));
  for (size_t i = 0; i < polygon.size(); ++i) {
    const Vec3& a = polygon[i];
    const Vec3& b = polygon[(i + 1) % polygon.size()];
    const Vec3& c = polygon[(i + 2) % polygon.size()];
    if (dot(cross(b - a, c - b), normal) < -1e-6f * size * size)
      return fmt::format("is not convex (it turns the other way at point {})", (i + 1) % polygon.size());
  }
  return {};
}

float boxTolerance(const Bounds3& box) { return 1e-4f * std::max(1.0f, maxComponent(box.diagonal())); }

std::string portalBoundaryProblem(const Bounds3& box, const std::vector<Vec3>& polygon) {
  const float tolerance = boxTolerance(box);
  const Bounds3 grown(box.lo - Vec3(tolerance), box.hi + Vec3(tolerance));
  for (size_t i = 0; i < polygon.size(); ++i)
    if (!grown.contains(polygon[i]))
      return fmt::format("point {} ({}, {}, {}) lies outside the box", i, polygon[i].x, polygon[i].y, polygon[i].z);
  for (int axis = 0; axis < 3; ++axis)
    for (const float plane : {box.lo[axis], box.hi[axis]}) {
      const bool onFace = std::all_of(polygon.begin(), polygon.end(),
                                      [&](const Vec3& p) { return std::abs(p[axis] - plane) <= tolerance; });
      if (onFace) return {};
    }
  return "lies inside the box, not on one of its faces";
}

}  // namespace portico
