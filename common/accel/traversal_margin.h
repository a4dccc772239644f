// The slab margin of the hierarchical traversals (kd_traverse.cpp,
// bvh_traverse.cpp): how far every box is grown, per ray, so that the box
// tests never drop a triangle the watertight test hits (see those files).
#pragma once

#include <cmath>

#include "common/math.h"

namespace portico {

// 2^-18 (64 float ulps) of the reach R, the largest distance per axis from
// the origin to the root box, plus 2^-20 (16 ulps) of the origin's largest
// coordinate, for the rounding of origin +- margin. This form takes R and
// the largest coordinate's magnitude.
//
// How much is enough was measured, not only argued: on nearly edge-on rays
// (accel_test::grazingRays, in the bvh and kd tests), the first hits the
// bvh dropped came with the reach term at 2^-22 and no origin term, or the
// origin term at 2^-24 and no reach term; 2^-18 keeps sixteen times that.
// A wider margin costs speed: photon rays leave surfaces by 2e-5 of their
// largest coordinate (surfaceOffset), which 2^-16 of R often exceeded, so
// every such ray tested its own surface's leaf first (bvh photon rays at
// 100k triangles 10 % slower, at 500k 8 %: docs/accelerator-benchmarks.md).
inline float traversalMargin(float reach, float magnitude) {
  constexpr float kMarginScale = 1.0f / 262144.0f;
  constexpr float kOriginMarginScale = 1.0f / 1048576.0f;
  return reach * kMarginScale + magnitude * kOriginMarginScale;
}

// The margin from the root box and the origin: reach and magnitude found here.
inline float traversalMargin(const Bounds3& root, const float origin[3]) {
  float reach = 0.0f, magnitude = 0.0f;
  for (int axis = 0; axis < 3; ++axis) {
    const float toLo = std::fabs(root.lo[axis] - origin[axis]), toHi = std::fabs(root.hi[axis] - origin[axis]);
    reach = reach > toLo ? reach : toLo;
    reach = reach > toHi ? reach : toHi;
    const float coordinate = std::fabs(origin[axis]);
    magnitude = magnitude > coordinate ? magnitude : coordinate;
  }
  return traversalMargin(reach, magnitude);
}

}  // namespace portico
