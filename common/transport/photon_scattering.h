// A photon of the photon pass, step by step: its emission from a light, and
// what it does at each surface it hits (a deposit, Russian roulette on the
// albedo, a cosine bounce). The cell kernel (CellKernel::emitPhotons and
// tracePhoton, cell by cell) and `portico bench pipeline`'s in-core tracer
// (the whole building in one Embree scene) both take these steps, so the two
// trace the same photons with the same random numbers and differ only in how
// they find the next surface.
#pragma once

#include <algorithm>
#include <cstdint>

#include "common/mesh_view.h"
#include "common/rng.h"
#include "common/scene/store/scene_types.h"
#include "common/transport/photon_map.h"
#include "common/transport/ray_state.h"
#include "common/transport/sampling.h"
#include "common/transport/surface_point.h"

namespace portico {

// Photon `path` leaving `light` (whose normal() is lightNormal): from a
// uniform point of the light, moved just off it, in a cosine-distributed
// direction, carrying `power` (the light's power over its photon count).
//
// A point luminaire's photon leaves its point in a direction drawn from its
// candela distribution (LuminousIntensity::sample, a cell by the light's two
// numbers, a direction within it by the direction's), so every photon
// carries the same power and their directions follow the intensity.
inline RayState emitPhoton(const AreaLight& light, const Vec3& lightNormal, const Vec3& power, uint64_t seed,
                           uint64_t path) {
  const float u = randomUniform(seed, RandomStream::Photon, path, 0, dim::LightU);
  const float v = randomUniform(seed, RandomStream::Photon, path, 0, dim::LightV);
  if (light.isPoint()) {
    const Vec3 local = light.intensity->sample(u, v, randomUniform(seed, RandomStream::Photon, path, 0, dim::DirectionU),
                                               randomUniform(seed, RandomStream::Photon, path, 0, dim::DirectionV));
    RayState photon;
    photon.kind = RayKind::Photon;
    photon.pathId = path;
    photon.origin = light.corner;
    photon.direction = normalize(light.fromLuminaire(local));
    photon.weight = power;
    return photon;
  }
  const Vec3 point = light.pointAt(u, v);
  RayState photon;
  photon.kind = RayKind::Photon;
  photon.pathId = path;
  photon.origin = offsetAlongNormal(point, lightNormal);
  photon.direction = sampleCosineHemisphere(lightNormal, randomUniform(seed, RandomStream::Photon, path, 0, dim::DirectionU),
                                            randomUniform(seed, RandomStream::Photon, path, 0, dim::DirectionV));
  photon.weight = power;
  return photon;
}

// Where a photon's segment ends: triangle `primitive` of `mesh`, at distance
// t along the photon's direction, made of `material`.
struct PhotonHit {
  const MeshView& mesh;
  uint32_t primitive;
  float t;
  float u, v;   // barycentrics of vertices 1 and 2
  const Material& material;
  // The albedo at the hit when the material is textured; null: material.albedo.
  const Vec3* albedo = nullptr;
};

// What the photon did at a surface.
struct PhotonScatter {
  bool deposited = false;   // `deposit` is the record to store
  StoredPhoton deposit;
  bool bounced = false;     // the photon is now its next segment; else it is absorbed
};

// Emitters and black surfaces absorb the photon and store nothing. Elsewhere
// it deposits, with the lit side's normal pointing into the surface (the
// estimates compare it with their own: photons on a wall meeting the floor
// do not count for the floor, and the irradiance cache knows the surface
// each of its points lies on). Then Russian roulette on the albedo: a
// survivor carries power * albedo / p, so the expected power is unchanged,
// and leaves in a cosine-distributed direction, unless it has made
// maxBounces - 1 bounces.
inline PhotonScatter scatterPhoton(RayState& photon, const PhotonHit& hit, uint64_t seed, uint32_t maxBounces) {
  PhotonScatter scatter;
  const Material& material = hit.material;
  const Vec3 albedo = hit.albedo ? *hit.albedo : material.albedo;
  if (material.emissive() || !(maxComponent(albedo) > 0)) return scatter;
  const Vec3 point = interiorHitPoint(hit.mesh, hit.primitive, hit.u, hit.v);
  const Vec3 geometric = normalize(hit.mesh.geometricNormal(hit.primitive));
  const Vec3 normal = dot(geometric, photon.direction) < 0 ? geometric : -geometric;
  scatter.deposited = true;
  // Member by member, not from a braced temporary: GCC built the temporary
  // with narrow stores and copied it with 16-byte loads, each waiting for
  // the stores it overlapped (~5 % of the function's samples each).
  scatter.deposit.position = point;
  scatter.deposit.direction = -normal;
  scatter.deposit.power = photon.weight;
  scatter.deposit.pathId = photon.pathId;
  scatter.deposit.bounce = photon.depth;
  const float survival = std::min(1.0f, maxComponent(albedo));
  const uint32_t bounce = photon.depth;
  if (randomUniform(seed, RandomStream::Photon, photon.pathId, bounce, dim::Roulette) >= survival ||
      bounce + 1u >= maxBounces)
    return scatter;
  scatter.bounced = true;
  photon.weight = photon.weight * albedo / survival;
  photon.depth = static_cast<uint16_t>(bounce + 1);
  photon.origin = offsetAlongNormal(point, normal);
  photon.direction =
      sampleCosineHemisphere(normal, randomUniform(seed, RandomStream::Photon, photon.pathId, photon.depth, dim::DirectionU),
                             randomUniform(seed, RandomStream::Photon, photon.pathId, photon.depth, dim::DirectionV));
  photon.tMin = 0;
  photon.tMax = kInfinity;
  return scatter;
}

}  // namespace portico
