// Triangle / axis-aligned box overlap by separating axes (Akenine-Möller,
// "Fast 3D Triangle-Box Overlap Testing", 2001): the triangle and the box are
// disjoint exactly when one of 13 axes separates them (the box's 3 face
// normals, the triangle's normal, and the 9 cross products of box and
// triangle edges).
//
// Used to bin triangles into voxel cells (scene import with --grid): the test
// is made conservative by growing the box by `tolerance` on every side, so
// that rounding can only add a triangle to a cell, never drop it.
#pragma once

#include "common/math.h"

namespace portico {

// Whether triangle (a, b, c) touches `box` grown by `tolerance` (>= 0) on
// every side. Touching counts: a triangle lying in a face of the box, or
// meeting it in one point, overlaps. A degenerate triangle (a segment or a
// point) is tested as such.
bool triangleOverlapsBox(const Vec3& a, const Vec3& b, const Vec3& c, const Bounds3& box, float tolerance);

}  // namespace portico
