// Where a ray or photon meets a triangle, as the point its bounce starts from.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "common/math.h"
#include "common/mesh_view.h"
#include "common/transport/sampling.h"

namespace portico {

// The hit point rebuilt from its barycentrics and pulled a hair towards the
// triangle's centroid. origin + t * direction can land a few ulps past the
// triangle's edge, and even the exact point of a hit on an edge where two
// walls meet lies on the other wall's plane: a bounce leaving it along the
// normal then starts on or behind that wall and, heading into it, passes
// through (a corner leak). Inside the triangle by 2e-5 of the coordinates'
// magnitude (the same reach as offsetAlongNormal), every neighbouring wall is
// strictly ahead. The shift is far below any pixel's or photon's scale.
inline Vec3 interiorHitPoint(const MeshView& mesh, uint32_t primitive, float u, float v) {
  Vec3 v0, v1, v2;
  mesh.triangle(primitive, v0, v1, v2);
  const Vec3 point = v0 + (v1 - v0) * u + (v2 - v0) * v;
  const Vec3 towardCentre = (v0 + v1 + v2) * (1.0f / 3.0f) - point;
  const float distance = std::sqrt(dot(towardCentre, towardCentre));
  if (!(distance > 0)) return point;
  return point + towardCentre * std::min(0.5f, surfaceOffset(point) / distance);
}

}  // namespace portico
