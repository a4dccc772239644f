// A ray in flight between cells: everything needed to finish it
// (common/net/ray_wire.h converts it to and from the wire).
#pragma once

#include <cmath>
#include <cstdint>

#include "common/math.h"

namespace portico {

enum class RayKind : uint8_t { Photon, Camera, Shadow, Gather };

struct RayState {
  RayKind kind = RayKind::Photon;
  uint16_t depth = 0;
  uint64_t pathId = 0;
  uint32_t pixel = 0;
  Vec3 origin, direction;   // direction is unit length
  float tMin = 0, tMax = kInfinity;
  Vec3 weight;              // photon power, camera/gather throughput, or shadow contribution
};

// A ray from the network is traced only if it is well formed.
inline bool isValid(const RayState& ray) {
  const float len = length(ray.direction);
  return ray.kind <= RayKind::Gather && isFinite(ray.origin) && isFinite(ray.weight) && std::isfinite(len) &&
         std::abs(len - 1.0f) < 1e-3f && !(ray.tMin < 0) && !(ray.tMax < ray.tMin);
}

}  // namespace portico
