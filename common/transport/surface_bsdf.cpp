#include "common/transport/surface_bsdf.h"

#include <cmath>
#include <map>
#include <memory>
#include <mutex>
#include <utility>

#include "common/transport/sampling.h"

namespace portico {

namespace {
inline Vec3 reflectAbout(const Vec3& w, const Vec3& m) { return m * (2.0f * dot(w, m)) - w; }

// The coating's reflectance (its specular albedo) and transmittance seen
// from cosine mu, index eta beyond it: the means of F G1(wo) and of
// (1 - F) G1(wt) over microfacets drawn from the visible normals (a 64 x 64
// stratified grid, the same numbers every time), wo and wt the reflected and
// refracted directions. Masking loses some of each, as Mitsuba 3's tables
// of its rough interfaces do.
struct Interface {
  float reflectance = 0, transmittance = 0;
};
Interface roughInterface(const Ggx& ggx, float eta, float mu) {
  const Vec3 wi(std::sqrt(std::max(0.0f, 1.0f - mu * mu)), 0.0f, mu);
  constexpr int kSide = 64;
  double reflected = 0, transmitted = 0;
  for (int i = 0; i < kSide; ++i)
    for (int j = 0; j < kSide; ++j) {
      const Vec3 m = ggx.sampleVisible(wi, (i + 0.5f) / kSide, (j + 0.5f) / kSide);
      const float cosI = dot(wi, m);
      const float f = fresnelDielectric(cosI, eta);
      const Vec3 wo = reflectAbout(wi, m);
      if (wo.z > 0) reflected += f * ggx.masking(wo, m);
      const float sin2T = (1.0f - cosI * cosI) / (eta * eta);
      if (sin2T >= 1.0f) continue;   // total internal reflection
      const float cosT = std::sqrt(1.0f - sin2T);
      const Vec3 wt = m * (cosI / eta - cosT) - wi * (1.0f / eta);
      if (wt.z < 0) transmitted += (1.0f - f) * ggx.masking(wt, m);
    }
  return {static_cast<float>(reflected / (kSide * kSide)), static_cast<float>(transmitted / (kSide * kSide))};
}

CoatingTable makeCoatingTable(float alpha, float eta) {
  CoatingTable table;
  const Ggx ggx{alpha};
  for (int i = 0; i < CoatingTable::kSize; ++i) {
    const float x = float(i) / float(CoatingTable::kSize - 1);
    const float mu = std::max(1e-4f, x * x);
    table.transmittance[i] = std::clamp(roughInterface(ggx, eta, mu).transmittance, 0.0f, 1.0f);
  }
  // Cosine-weighted means, 2 int f(mu) mu dmu: of t over the table's own
  // interpolation (fine midpoints), and of the inside's reflectance (index
  // 1 / eta, total internal reflection included) as Mitsuba 3 takes it,
  // twice the mean of f(mu) mu over 64 evenly spaced mu from 0 to 1.
  constexpr int kSteps = 1024;
  double transmitted = 0, reflectedInside = 0;
  for (int s = 0; s < kSteps; ++s) {
    const float mu = (s + 0.5f) / kSteps;
    transmitted += 2.0 * table.at(mu) * mu / kSteps;
  }
  constexpr int kInside = 64;
  for (int s = 0; s < kInside; ++s) {
    const float mu = std::max(1e-6f, float(s) / float(kInside - 1));
    reflectedInside += 2.0 * roughInterface(ggx, 1.0f / eta, mu).reflectance * mu / kInside;
  }
  table.uniformTransmittance = static_cast<float>(transmitted);
  table.internalReflectance = static_cast<float>(reflectedInside);
  return table;
}
}  // namespace

float CoatingTable::at(float cosine) const {
  const float x = std::sqrt(std::clamp(cosine, 0.0f, 1.0f)) * float(kSize - 1);
  const int i = std::min(static_cast<int>(x), kSize - 2);
  const float w = x - float(i);
  return transmittance[i] * (1.0f - w) + transmittance[i + 1] * w;
}

const CoatingTable& coatingTable(float alpha, float eta) {
  static std::mutex mutex;
  static std::map<std::pair<float, float>, std::unique_ptr<CoatingTable>> tables;
  const std::lock_guard lock(mutex);
  auto& table = tables[{alpha, eta}];
  if (!table) table = std::make_unique<CoatingTable>(makeCoatingTable(alpha, eta));
  return *table;
}

SurfaceBsdf::SurfaceBsdf(const Material& material, const Vec3& albedo, const Vec3& normal, const Vec3& toViewer,
                         const CoatingTable* table)
    : finish_(material.finish), mirror_(material.mirror()), normal_(normal), specular_(material.specular),
      ggx_{ggxAlpha(material.roughness)}, eta_(material.ior), table_(table) {
  orthonormalBasis(normal_, tangent_, bitangent_);
  viewer_ = toLocal(toViewer);
  viewer_.z = std::max(viewer_.z, 1e-6f);
  switch (finish_) {
    case Finish::Matte: diffuseScale_ = albedo; break;
    case Finish::Plastic:
      if (!table_) table_ = &coatingTable(ggx_.alpha, eta_);
      viewerTransmittance_ = table_->at(viewer_.z);
      diffuseScale_ = albedo / (eta_ * eta_ * (1.0f - table_->internalReflectance));
      break;
    case Finish::Metal: conductor_ = conductorFromReflectance(specular_); break;
  }
}

Vec3 SurfaceBsdf::fresnel(float cosine) const {
  if (finish_ == Finish::Metal) return fresnelConductor(cosine, conductor_);
  return specular_ * fresnelDielectric(cosine, eta_);
}

Vec3 SurfaceBsdf::diffuseAlbedo() const {
  if (finish_ == Finish::Plastic) return diffuseScale_ * (table_->uniformTransmittance * viewerTransmittance_);
  return diffuseScale_;
}

Vec3 SurfaceBsdf::diffuseWeight(const Vec3& wi) const {
  const float cosI = dot(wi, normal_);
  if (cosI <= 0) return Vec3(0.0f);
  if (finish_ != Finish::Plastic) return diffuseScale_;
  return diffuseScale_ * (table_->at(cosI) * viewerTransmittance_);
}

Vec3 SurfaceBsdf::glossy(const Vec3& wi) const {
  if (finish_ == Finish::Matte || mirror_) return Vec3(0.0f);
  const Vec3 in = toLocal(wi);
  if (in.z <= 0) return Vec3(0.0f);
  const Vec3 m = normalize(in + viewer_);
  const float g = ggx_.masking(viewer_, m) * ggx_.masking(in, m);
  if (!(g > 0)) return Vec3(0.0f);
  return fresnel(dot(viewer_, m)) * (ggx_.density(m) * g / (4.0f * viewer_.z * in.z));
}

float SurfaceBsdf::glossyPdf(const Vec3& wi) const {
  if (finish_ == Finish::Matte || mirror_) return 0;
  return ggx_.reflectedPdf(viewer_, toLocal(wi));
}

SurfaceBsdf::Sample SurfaceBsdf::sampleGlossy(float u1, float u2) const {
  Sample sample;
  if (finish_ == Finish::Matte) return sample;
  if (mirror_) {
    sample.direction = toWorld(Vec3(-viewer_.x, -viewer_.y, viewer_.z));
    sample.weight = fresnel(viewer_.z);
    return sample;
  }
  const Vec3 m = ggx_.sampleVisible(viewer_, u1, u2);
  const Vec3 out = reflectAbout(viewer_, m);
  if (out.z <= 0) return sample;
  sample.direction = normalize(toWorld(out));
  // f_s cos / pdf = F G1(out) (the viewer's G1 and D cancel).
  sample.weight = fresnel(dot(viewer_, m)) * ggx_.masking(out, m);
  sample.pdf = ggx_.reflectedPdf(viewer_, out);
  return sample;
}

float SurfaceBsdf::glossyShare() const {
  switch (finish_) {
    case Finish::Matte: return 0;
    case Finish::Plastic: return 1.0f - viewerTransmittance_;
    case Finish::Metal: return 1;
  }
  return 0;
}

Vec3 SurfaceBsdf::diffuseContinuation(const Vec3& wi) const {
  // Chosen with probability t(cos_o): pi f_d / t(cos_o).
  if (finish_ != Finish::Plastic) return diffuseWeight(wi);
  return diffuseWeight(wi) / std::max(viewerTransmittance_, 1e-6f);
}

}  // namespace portico
