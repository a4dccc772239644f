// A ray in flight between cells, and its conversions to and from the wire.
#pragma once

#include <cstdint>

#include "common/math.h"
#include "proto/wire.capnp.h"

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

inline void toWire(const RayState& ray, wire::Ray::Builder out) {
  out.setKind(static_cast<wire::RayKind>(ray.kind));
  out.setDepth(ray.depth);
  out.setPathId(ray.pathId);
  out.setPixel(ray.pixel);
  out.setOx(ray.origin.x);
  out.setOy(ray.origin.y);
  out.setOz(ray.origin.z);
  out.setDx(ray.direction.x);
  out.setDy(ray.direction.y);
  out.setDz(ray.direction.z);
  out.setTMin(ray.tMin);
  out.setTMax(ray.tMax);
  out.setR(ray.weight.x);
  out.setG(ray.weight.y);
  out.setB(ray.weight.z);
}

inline RayState fromWire(wire::Ray::Reader in) {
  RayState ray;
  ray.kind = static_cast<RayKind>(in.getKind());
  ray.depth = in.getDepth();
  ray.pathId = in.getPathId();
  ray.pixel = in.getPixel();
  ray.origin = {in.getOx(), in.getOy(), in.getOz()};
  ray.direction = {in.getDx(), in.getDy(), in.getDz()};
  ray.tMin = in.getTMin();
  ray.tMax = in.getTMax();
  ray.weight = {in.getR(), in.getG(), in.getB()};
  return ray;
}

// A ray from the network is traced only if it is well formed.
inline bool isValid(const RayState& ray) {
  const float len = length(ray.direction);
  return ray.kind <= RayKind::Gather && isFinite(ray.origin) && isFinite(ray.weight) && std::isfinite(len) &&
         std::abs(len - 1.0f) < 1e-3f && !(ray.tMin < 0) && !(ray.tMax < ray.tMin);
}

}  // namespace portico
