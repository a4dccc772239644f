// Squared distances from one query point to kLanes stored points at once,
// for the buckets of PointKdTree. Coordinates come as three arrays (x, y,
// z); the result is bit-identical to dot(point - p, point - p) of math.h
// ((dx*dx + dy*dy) + dz*dz, no fused multiply-add), so the vector and the
// scalar code give the same answers.
#pragma once

#include <cstdint>

#include "common/math.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace portico {

class PointLanes {
 public:
  static constexpr uint32_t kLanes = 4;

  explicit PointLanes(const Vec3& p) : p_(p) {
#if defined(__SSE2__)
    px_ = _mm_set1_ps(p.x);
    py_ = _mm_set1_ps(p.y);
    pz_ = _mm_set1_ps(p.z);
#endif
  }

  // Writes the squared distances of points (x[i], y[i], z[i]), i < kLanes,
  // to distanceSquared and returns a mask with bit i set when the i-th is
  // <= bound (never for a NaN coordinate).
  uint32_t within(const float* x, const float* y, const float* z, float bound, float* distanceSquared) const {
#if defined(__SSE2__)
    const __m128 dx = _mm_sub_ps(_mm_loadu_ps(x), px_);
    const __m128 dy = _mm_sub_ps(_mm_loadu_ps(y), py_);
    const __m128 dz = _mm_sub_ps(_mm_loadu_ps(z), pz_);
    const __m128 d2 = _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz));
    _mm_storeu_ps(distanceSquared, d2);
    return static_cast<uint32_t>(_mm_movemask_ps(_mm_cmple_ps(d2, _mm_set1_ps(bound))));
#else
    uint32_t mask = 0;
    for (uint32_t i = 0; i < kLanes; ++i) {
      const Vec3 offset = Vec3(x[i], y[i], z[i]) - p_;
      distanceSquared[i] = dot(offset, offset);
      mask |= uint32_t{distanceSquared[i] <= bound} << i;
    }
    return mask;
#endif
  }

 private:
  Vec3 p_;
#if defined(__SSE2__)
  __m128 px_, py_, pz_;
#endif
};

}  // namespace portico
