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
  // Portals crossed (camera rays) or bounces; a gather ray's may carry
  // kSecondaryGatherDepth. Its top bit is the wire's (ray_wire.h).
  uint16_t depth = 0;
  uint64_t pathId = 0;
  uint32_t pixel = 0;
  Vec3 origin, direction;   // direction is unit length
  float tMin = 0, tMax = kInfinity;
  Vec3 weight;              // photon power, camera/gather throughput, or shadow contribution
  // Daylight's rays towards the sky, which the building's outdoors may
  // shadow (outdoor_passage.h). A shadow ray: its light is the sky beyond
  // an opening; it may not go outdoors before tMax (the opening it
  // samples: the sky seen there is that opening's), and at tMax it goes on
  // (tMax infinite) until it leaves the building, reaching its light only
  // then. A photon: the way back from where a daylight photon starts on an
  // opening, against its direction (`pixel` holds the cell it starts in);
  // where it leaves the building the photon starts, and where something
  // outdoors is in its way it is absorbed there.
  bool toSky = false;
};

// The depth bit of a short gather's own gather ray (CellKernel): read
// wherever it lands, it starts no further recursion. It crosses portals
// inside `depth`, below the wire's toSky bit.
inline constexpr uint16_t kSecondaryGatherDepth = 0x4000;
inline bool isSecondaryGather(const RayState& ray) {
  return ray.kind == RayKind::Gather && (ray.depth & kSecondaryGatherDepth) != 0;
}

// A ray from the network is traced only if it is well formed.
inline bool isValid(const RayState& ray) {
  const float len = length(ray.direction);
  return ray.kind <= RayKind::Gather && isFinite(ray.origin) && isFinite(ray.weight) && std::isfinite(len) &&
         std::abs(len - 1.0f) < 1e-3f && !(ray.tMin < 0) && !(ray.tMax < ray.tMin);
}

}  // namespace portico
