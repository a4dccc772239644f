#include "common/triangle_box_overlap.h"

#include <algorithm>
#include <cmath>

namespace portico {

bool triangleOverlapsBoxBeyondBounds(const Double3& center, const Double3& halfSize, const Double3& v0,
                                     const Double3& v1, const Double3& v2) {
  const Double3 a = v0 - center, b = v1 - center, c = v2 - center;
  // A zero axis separates nothing.
  const auto separatedOn = [&](const Double3& axis) {
    const double pa = dot(axis, a), pb = dot(axis, b), pc = dot(axis, c);
    const double radius =
        halfSize.x * std::fabs(axis.x) + halfSize.y * std::fabs(axis.y) + halfSize.z * std::fabs(axis.z);
    return std::min({pa, pb, pc}) > radius || std::max({pa, pb, pc}) < -radius;
  };
  // Box edge x triangle edge: cross(x, e), cross(y, e), cross(z, e).
  const Double3 edges[3] = {b - a, c - b, a - c};
  for (const Double3& e : edges)
    if (separatedOn({0.0, -e.z, e.y}) || separatedOn({e.z, 0.0, -e.x}) || separatedOn({-e.y, e.x, 0.0}))
      return false;
  // The triangle's plane.
  return !separatedOn(cross(edges[0], edges[1]));
}

bool triangleOverlapsBox(const Vec3& a, const Vec3& b, const Vec3& c, const Bounds3& box, float tolerance) {
  const Double3 center{0.5 * (double(box.lo.x) + box.hi.x), 0.5 * (double(box.lo.y) + box.hi.y),
                       0.5 * (double(box.lo.z) + box.hi.z)};
  const Double3 half{0.5 * (double(box.hi.x) - box.lo.x) + tolerance,
                     0.5 * (double(box.hi.y) - box.lo.y) + tolerance,
                     0.5 * (double(box.hi.z) - box.lo.z) + tolerance};
  const Double3 v[3] = {toDouble(a) - center, toDouble(b) - center, toDouble(c) - center};
  // The box's face normals: the triangle's bounds against the box.
  for (int axis = 0; axis < 3; ++axis) {
    const double lo = std::min({v[0][axis], v[1][axis], v[2][axis]});
    const double hi = std::max({v[0][axis], v[1][axis], v[2][axis]});
    if (lo > half[axis] || hi < -half[axis]) return false;
  }
  return triangleOverlapsBoxBeyondBounds(center, half, toDouble(a), toDouble(b), toDouble(c));
}

}  // namespace portico
