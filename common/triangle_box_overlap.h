// Triangle / axis-aligned box overlap by separating axes (Akenine-Möller,
// "Fast 3D Triangle-Box Overlap Testing", 2001): the triangle and the box are
// disjoint exactly when one of 13 axes separates them (the box's 3 face
// normals, the triangle's normal, and the 9 cross products of box and
// triangle edges). Computed in double from float input, so that with a
// tolerance added to the box, rounding can only add a triangle to a box,
// never drop it. Used to bin triangles into grid voxels (the uniform and
// hierarchical grids) and into voxel cells (scene import with --grid).
#pragma once

#include "common/math.h"

namespace portico {

struct Double3 {
  double x = 0, y = 0, z = 0;
  double operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
};
inline Double3 operator-(const Double3& a, const Double3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline double dot(const Double3& a, const Double3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Double3 cross(const Double3& a, const Double3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline Double3 toDouble(const Vec3& v) { return {v.x, v.y, v.z}; }

// The triangle's plane and the 9 edge cross products only: for callers that
// already know the triangle's bounds meet the box (a grid visiting the
// voxels of a triangle's grown bounding box), the box's face normals cannot
// separate them. Touching counts as overlapping.
bool triangleOverlapsBoxBeyondBounds(const Double3& center, const Double3& halfSize, const Double3& v0,
                                     const Double3& v1, const Double3& v2);

// All 13 axes: whether triangle (a, b, c) touches `box` grown by `tolerance`
// (>= 0) on every side. A degenerate triangle (a segment or a point) is
// tested as such.
bool triangleOverlapsBox(const Vec3& a, const Vec3& b, const Vec3& c, const Bounds3& box, float tolerance);

}  // namespace portico
