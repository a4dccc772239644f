// How a surface reflects: its material's finish (Material::finish) at one
// point, seen from one side. Matte is Lambertian. Plastic is a rough
// dielectric coating over a diffuse base, as Mitsuba's roughplastic: a GGX
// specular lobe with the coating's Fresnel reflectance (times `specular`),
// plus the base's light that the coating lets out,
//   f_d = albedo t(cos_i) t(cos_o) / (pi eta^2 (1 - R_int)),
// t the rough coating's transmittance and R_int the cosine-weighted mean of
// its reflectance from inside, both tabulated with Smith's masking as
// Mitsuba 3 does (so a plastic loses what masking loses and reflects no
// more than it receives). Metal is a GGX conductor (Fresnel of the index
// fitted to `specular`, fresnel.h); roughness 0 is a perfect mirror.
//
// Transport splits it: photon estimates and gather rays see the diffuse
// part (the photon map holds light arriving at diffuse surfaces); camera and
// gather paths carry on through the glossy part by sampling it.
#pragma once

#include <algorithm>
#include <cstdint>

#include "common/math.h"
#include "common/scene/store/scene_types.h"
#include "common/transport/fresnel.h"
#include "common/transport/microfacet.h"

namespace portico {

// The GGX alpha of a rough finish: its perceptual roughness squared, kept
// above 0.01 (narrower lobes are mirrors in all but name, and no light
// sampling or float pdf copes with them).
inline float ggxAlpha(float roughness) { return std::max(roughness * roughness, 0.01f); }

// A coating's transmittance t(cos) and internal reflectance (computed once
// per alpha and index for the process and kept: coatingTable).
struct CoatingTable {
  static constexpr int kSize = 64;
  // At cos = x^2, x = i / (kSize - 1): dense towards grazing, where t
  // changes fastest (a uniform grid there let a smooth white plastic
  // reflect 0.4 % more than it received).
  float transmittance[kSize];
  float internalReflectance = 0;
  float uniformTransmittance = 0;   // the cosine-weighted mean of t
  float at(float cosine) const;
};
const CoatingTable& coatingTable(float alpha, float eta);

class SurfaceBsdf {
 public:
  // normal: the side light leaves to (towards `toViewer`, unit); albedo:
  // the diffuse albedo there (a texture's when it has one). table: the
  // material's coating (plastic only; coatingTable).
  SurfaceBsdf(const Material& material, const Vec3& albedo, const Vec3& normal, const Vec3& toViewer,
              const CoatingTable* table = nullptr);

  Finish finish() const { return finish_; }
  bool mirror() const { return mirror_; }
  bool hasDiffuse() const { return maxComponent(diffuseScale_) > 0; }
  bool hasGlossy() const { return finish_ != Finish::Matte; }
  // The diffuse part's albedo under uniform light: what photon estimates
  // multiply irradiance / pi by (matte: albedo; plastic: albedo t(cos_o)
  // times the coating's mean t over eta^2 (1 - R_int)).
  Vec3 diffuseAlbedo() const;
  // pi f_d(wi): the weight of a cosine-distributed gather ray along wi.
  Vec3 diffuseWeight(const Vec3& wi) const;
  // f_s(wi), the glossy part (0 for a mirror, whose lobe is a direction).
  Vec3 glossy(const Vec3& wi) const;
  // The pdf (solid angle) with which sampleGlossy draws wi; 0 for a mirror.
  float glossyPdf(const Vec3& wi) const;
  struct Sample {
    Vec3 direction;
    Vec3 weight;    // f_s cos / pdf (a mirror: its Fresnel reflectance); 0 when it has none
    float pdf = 0;  // 0 for a mirror's direction
  };
  Sample sampleGlossy(float u1, float u2) const;
  // The glossy part's share of the light: the probability with which a
  // photon or gather ray reaching the surface goes on by it (plastic:
  // 1 - t(cos_o); metal: 1).
  float glossyShare() const;
  // A photon that continues by the diffuse part (with probability 1 -
  // glossyShare()): its cosine-distributed direction's weight along wi.
  Vec3 diffuseContinuation(const Vec3& wi) const;

 private:
  Vec3 toLocal(const Vec3& v) const { return {dot(v, tangent_), dot(v, bitangent_), dot(v, normal_)}; }
  Vec3 toWorld(const Vec3& v) const { return tangent_ * v.x + bitangent_ * v.y + normal_ * v.z; }
  Vec3 fresnel(float cosine) const;

  Finish finish_;
  bool mirror_;
  Vec3 normal_, tangent_, bitangent_;
  Vec3 viewer_;   // local
  Vec3 diffuseScale_;   // f_d = diffuseScale_ t(cos_i) t(cos_o) / pi (matte: albedo, t = 1)
  Vec3 specular_;
  Ggx ggx_;
  float eta_ = 1.5f;
  ConductorIndex conductor_;
  const CoatingTable* table_ = nullptr;
  float viewerTransmittance_ = 1;
};

}  // namespace portico
