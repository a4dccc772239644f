#include "common/transport/photon_scattering.h"

namespace portico {

PhotonScatter scatterGlossyPhoton(RayState& photon, const PhotonHit& hit, const Vec3& albedo, uint64_t seed,
                                  uint32_t maxBounces) {
  PhotonScatter scatter;
  const Vec3 point = interiorHitPoint(hit.mesh, hit.primitive, hit.u, hit.v);
  const Vec3 geometric = normalize(hit.mesh.geometricNormal(hit.primitive));
  const Vec3 normal = dot(geometric, photon.direction) < 0 ? geometric : -geometric;
  const SurfaceBsdf bsdf(hit.material, albedo, normal, -photon.direction, hit.coating);
  const uint32_t bounce = photon.depth;
  if (bsdf.hasDiffuse()) {
    scatter.deposited = true;
    scatter.deposit.position = point;
    scatter.deposit.direction = -normal;
    scatter.deposit.power = photon.weight;
    scatter.deposit.pathId = photon.pathId;
    scatter.deposit.bounce = photon.depth;
  }
  if (bounce + 1u >= maxBounces) return scatter;
  const auto number = [&](uint32_t dimension) {
    return randomUniform(seed, RandomStream::Photon, photon.pathId, bounce + 1, dimension);
  };
  Vec3 direction, factor;
  const float share = bsdf.glossyShare();
  if (number(dim::LobeChoice) < share) {
    const SurfaceBsdf::Sample sample = bsdf.sampleGlossy(number(dim::LobeU), number(dim::LobeV));
    direction = sample.direction;
    factor = sample.weight / share;
  } else {
    direction = sampleCosineHemisphere(normal, number(dim::DirectionU), number(dim::DirectionV));
    factor = bsdf.diffuseContinuation(direction);
  }
  const float survival = std::min(1.0f, maxComponent(factor));
  if (!(survival > 0) || randomUniform(seed, RandomStream::Photon, photon.pathId, bounce, dim::Roulette) >= survival)
    return scatter;
  scatter.bounced = true;
  photon.weight = photon.weight * factor / survival;
  photon.depth = static_cast<uint16_t>(bounce + 1);
  photon.origin = offsetAlongNormal(point, normal);
  photon.direction = direction;
  photon.tMin = 0;
  photon.tMax = kInfinity;
  return scatter;
}

}  // namespace portico
