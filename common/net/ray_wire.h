// A ray in flight between cells (common/transport/ray_state.h) and its
// wire form (wire::Ray): the transport code knows nothing of the wire.
#pragma once

#include "common/transport/ray_state.h"
#include "proto/wire.capnp.h"

namespace portico {

inline constexpr uint16_t kToSkyBit = 0x8000, kDepthBits = 0x7fff;
// A secondary gather's mark travels in the depth the wire keeps.
static_assert((kSecondaryGatherDepth & kDepthBits) == kSecondaryGatherDepth);

inline void toWire(const RayState& ray, wire::Ray::Builder out) {
  out.setKind(static_cast<wire::RayKind>(ray.kind));
  // A ray towards the sky (RayState::toSky) travels as the top bit of its
  // depth: no ray is 32 768 bounces or portals deep.
  out.setDepth(static_cast<uint16_t>((ray.depth & kDepthBits) | (ray.toSky ? kToSkyBit : 0)));
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
  ray.depth = in.getDepth() & kDepthBits;
  ray.toSky = (in.getDepth() & kToSkyBit) != 0;
  ray.pathId = in.getPathId();
  ray.pixel = in.getPixel();
  ray.origin = {in.getOx(), in.getOy(), in.getOz()};
  ray.direction = {in.getDx(), in.getDy(), in.getDz()};
  ray.tMin = in.getTMin();
  ray.tMax = in.getTMax();
  ray.weight = {in.getR(), in.getG(), in.getB()};
  return ray;
}

}  // namespace portico
