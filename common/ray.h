// The ray and hit records every accelerator speaks.
#pragma once

#include <cstdint>

#include "common/math.h"

namespace portico {

struct Ray {
  Vec3 origin;
  Vec3 direction;       // need not be normalised; t is in units of |direction|
  float tMin = 0.0f;    // hits count only for tMin < t < tMax
  float tMax = kInfinity;
};

constexpr uint32_t kNoPrimitive = 0xffffffffu;

struct Hit {
  float t = kInfinity;
  uint32_t primitive = kNoPrimitive;
  float u = 0, v = 0;   // barycentrics of vertices 1 and 2

  bool found() const { return primitive != kNoPrimitive; }
};

// The one tie-break of portico: nearer t wins; at equal t the smaller
// primitive id wins. Every accelerator uses it, so all return the same hit.
inline bool closerThan(float t, uint32_t primitive, const Hit& best) {
  return t < best.t || (t == best.t && primitive < best.primitive);
}

}  // namespace portico
