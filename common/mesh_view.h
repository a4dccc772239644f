// A backend-neutral view of a cell's triangles (after Mitsuba's ShapeIR):
// every accelerator is built from the same view. The arrays are not owned;
// they usually point into an mmap'd cell file and must outlive the view.
#pragma once

#include <cstddef>
#include <cstdint>

#include "common/math.h"

namespace portico {

struct MeshView {
  const float* positions = nullptr;   // xyz per vertex, packed
  size_t vertexCount = 0;
  const uint32_t* indices = nullptr;  // 3 vertex indices per triangle
  size_t triangleCount = 0;
  // Floats that may be read past the last vertex (positions[3 * vertexCount]
  // onwards) without leaving the allocation: Embree reads float3 vertex
  // buffers with 16-byte loads, so it can share `positions` only when this is
  // at least 1 (else it copies them). Their values do not matter. 0 when unknown.
  size_t positionsPaddingFloats = 0;

  Vec3 vertex(uint32_t i) const {
    const float* p = positions + 3 * static_cast<size_t>(i);
    return {p[0], p[1], p[2]};
  }
  void triangle(uint32_t primitive, Vec3& v0, Vec3& v1, Vec3& v2) const {
    const uint32_t* t = indices + 3 * static_cast<size_t>(primitive);
    v0 = vertex(t[0]);
    v1 = vertex(t[1]);
    v2 = vertex(t[2]);
  }
  Bounds3 triangleBounds(uint32_t primitive) const {
    Vec3 a, b, c;
    triangle(primitive, a, b, c);
    Bounds3 box(a, a);
    box.extend(b);
    box.extend(c);
    return box;
  }
  // Unnormalised geometric normal (v1 - v0) x (v2 - v0): the winding decides the front.
  Vec3 geometricNormal(uint32_t primitive) const {
    Vec3 a, b, c;
    triangle(primitive, a, b, c);
    return cross(b - a, c - a);
  }
};

}  // namespace portico
