// Separating-axis triangle/box test (see the header). Computed in double:
// it runs once per (triangle, candidate voxel) at import, not while tracing,
// and double keeps the rounding far below the tolerance the caller adds.
#include "common/scene/triangle_box_overlap.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace portico {

namespace {

struct Vec3d {
  double x = 0, y = 0, z = 0;
  double operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
};

Vec3d sub(const Vec3& p, const Vec3d& origin) { return {p.x - origin.x, p.y - origin.y, p.z - origin.z}; }
Vec3d sub(const Vec3d& a, const Vec3d& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
Vec3d cross(const Vec3d& a, const Vec3d& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
double dot(const Vec3d& a, const Vec3d& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

// Whether `axis` separates the triangle (vertices relative to the box centre)
// from the box of half-extents `half`. A zero axis separates nothing.
bool separates(const Vec3d& axis, const std::array<Vec3d, 3>& v, const Vec3d& half) {
  const double p0 = dot(axis, v[0]), p1 = dot(axis, v[1]), p2 = dot(axis, v[2]);
  const double radius = half.x * std::abs(axis.x) + half.y * std::abs(axis.y) + half.z * std::abs(axis.z);
  return std::min({p0, p1, p2}) > radius || std::max({p0, p1, p2}) < -radius;
}

}  // namespace

bool triangleOverlapsBox(const Vec3& a, const Vec3& b, const Vec3& c, const Bounds3& box, float tolerance) {
  const Vec3d center{0.5 * (double(box.lo.x) + box.hi.x), 0.5 * (double(box.lo.y) + box.hi.y),
                     0.5 * (double(box.lo.z) + box.hi.z)};
  const Vec3d half{0.5 * (double(box.hi.x) - box.lo.x) + tolerance, 0.5 * (double(box.hi.y) - box.lo.y) + tolerance,
                   0.5 * (double(box.hi.z) - box.lo.z) + tolerance};
  const std::array<Vec3d, 3> v{sub(a, center), sub(b, center), sub(c, center)};

  // The box's face normals: the triangle's bounds against the box.
  for (int axis = 0; axis < 3; ++axis) {
    const double lo = std::min({v[0][axis], v[1][axis], v[2][axis]});
    const double hi = std::max({v[0][axis], v[1][axis], v[2][axis]});
    if (lo > half[axis] || hi < -half[axis]) return false;
  }
  const std::array<Vec3d, 3> edges{sub(v[1], v[0]), sub(v[2], v[1]), sub(v[0], v[2])};
  // The triangle's plane.
  if (separates(cross(edges[0], edges[1]), v, half)) return false;
  // Box edge x triangle edge.
  const std::array<Vec3d, 3> boxAxes{Vec3d{1, 0, 0}, Vec3d{0, 1, 0}, Vec3d{0, 0, 1}};
  for (const Vec3d& boxAxis : boxAxes)
    for (const Vec3d& edge : edges)
      if (separates(cross(boxAxis, edge), v, half)) return false;
  return true;
}

}  // namespace portico
