// Glossy finishes (surface_bsdf.h): no finish of albedo 1 reflects more
// than it receives (a white furnace, from every angle), sampling agrees with
// evaluation, a mirror reflects its Fresnel about the normal, and the metal
// fit gives its colour at normal incidence.
#include <gtest/gtest.h>

#include <cmath>

#include "common/transport/fresnel.h"
#include "common/transport/sampling.h"
#include "common/transport/surface_bsdf.h"

namespace portico {
namespace {

const Vec3 kNormal(0.0f, 1.0f, 0.0f);

Material finish(Finish kind, float roughness, const Vec3& albedo = Vec3(1.0f), const Vec3& specular = Vec3(1.0f)) {
  Material material;
  material.albedo = albedo;
  material.finish = kind;
  material.specular = specular;
  material.roughness = roughness;
  return material;
}

Vec3 viewerAt(float cosine) { return normalize(Vec3(std::sqrt(1.0f - cosine * cosine), cosine, 0.0f)); }

// The light a finish reflects towards the viewer under a uniform field of
// radiance 1 (its directional albedo): the glossy part by its own sampling
// (mean weight), the diffuse part by cosine sampling (mean pi f_d), each
// over a stratified n x n grid.
Vec3 reflectedOfUniformLight(const SurfaceBsdf& bsdf, int n = 128) {
  Vec3 glossy, diffuse;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const float u = (i + 0.5f) / n, v = (j + 0.5f) / n;
      glossy += bsdf.sampleGlossy(u, v).weight;
      diffuse += bsdf.diffuseWeight(sampleCosineHemisphere(kNormal, u, v));
    }
  return (glossy + diffuse) / float(n * n);
}

TEST(SurfaceBsdf, WhiteFinishesNeverReflectMoreThanTheyReceive) {
  for (const float roughness : {0.0f, 0.05f, 0.2f, 0.5f, 1.0f})
    for (const float ior : {1.2f, 1.5f, 2.4f})
      for (const float cosine : {0.02f, 0.1f, 0.3f, 0.6f, 0.9f, 1.0f}) {
        Material plastic = finish(Finish::Plastic, roughness);
        plastic.ior = ior;
        const Vec3 plasticAlbedo = reflectedOfUniformLight(SurfaceBsdf(plastic, plastic.albedo, kNormal, viewerAt(cosine)));
        const Material metal = finish(Finish::Metal, roughness, Vec3(0.0f), Vec3(1.0f));
        const Vec3 metalAlbedo = reflectedOfUniformLight(SurfaceBsdf(metal, metal.albedo, kNormal, viewerAt(cosine)));
        SCOPED_TRACE(::testing::Message() << "roughness " << roughness << " ior " << ior << " cos " << cosine);
        EXPECT_LE(maxComponent(plasticAlbedo), 1.0f + 2e-3f);
        EXPECT_LE(maxComponent(metalAlbedo), 1.0f + 2e-3f);
        // ... and not nothing: a white plastic loses what masking takes
        // from its coating's reflection and transmission (most at grazing
        // angles and high roughness, as Mitsuba's roughplastic).
        EXPECT_GT(plasticAlbedo.x, cosine >= 0.3f && roughness <= 0.5f ? 0.5f : 0.1f);
      }
}

TEST(SurfaceBsdf, TheDiffusePartReflectsItsAlbedoUnderUniformLight) {
  const Material plastic = finish(Finish::Plastic, 0.3f, Vec3(0.6f, 0.4f, 0.2f));
  for (const float cosine : {0.1f, 0.5f, 1.0f}) {
    const SurfaceBsdf bsdf(plastic, plastic.albedo, kNormal, viewerAt(cosine));
    Vec3 sum;
    constexpr int n = 256;
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) sum += bsdf.diffuseWeight(sampleCosineHemisphere(kNormal, (i + 0.5f) / n, (j + 0.5f) / n));
    const Vec3 mean = sum / float(n * n), expected = bsdf.diffuseAlbedo();
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(mean[c], expected[c], 2e-3f * expected[c]) << c << " cos " << cosine;
  }
}

// The glossy part's samples estimate what evaluating it over the sphere does.
TEST(SurfaceBsdf, GlossySamplingAgreesWithEvaluation) {
  for (const Finish kind : {Finish::Plastic, Finish::Metal}) {
    const Material material = finish(kind, 0.5f, Vec3(0.5f), Vec3(0.9f, 0.7f, 0.5f));
    const SurfaceBsdf bsdf(material, material.albedo, kNormal, viewerAt(0.7f));
    Vec3 sampled, evaluated;
    double pdfIntegral = 0, below = 0;   // below: samples reflected under the horizon
    constexpr int n = 400;
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        const float u = (i + 0.5f) / n, v = (j + 0.5f) / n;
        const SurfaceBsdf::Sample sample = bsdf.sampleGlossy(u, v);
        sampled += sample.weight;
        below += !(sample.pdf > 0);
        // Uniform over the hemisphere: pdf 1 / (2 pi).
        const float z = u, r = std::sqrt(1.0f - z * z), phi = 2.0f * kPi * v;
        const Vec3 wi(r * std::cos(phi), z, r * std::sin(phi));
        evaluated += bsdf.glossy(wi) * (z * 2.0f * kPi);
        pdfIntegral += bsdf.glossyPdf(wi) * 2.0 * kPi;
      }
    sampled = sampled / float(n * n);
    evaluated = evaluated / float(n * n);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(sampled[c], evaluated[c], 0.01f * evaluated[c]) << int(kind) << " " << c;
    // The pdf integrates to the share of samples that stay above the horizon.
    EXPECT_NEAR(pdfIntegral / (n * n), 1.0 - below / (n * n), 0.01) << int(kind);
  }
}

TEST(SurfaceBsdf, AMirrorReflectsItsFresnelAboutTheNormal) {
  const Material mirror = finish(Finish::Metal, 0.0f, Vec3(0.0f), Vec3(0.9f, 0.6f, 0.3f));
  ASSERT_TRUE(mirror.mirror());
  const Vec3 toViewer = viewerAt(0.8f);
  const SurfaceBsdf bsdf(mirror, mirror.albedo, kNormal, toViewer);
  const SurfaceBsdf::Sample sample = bsdf.sampleGlossy(0.3f, 0.7f);
  const Vec3 expected = kNormal * (2.0f * dot(toViewer, kNormal)) - toViewer;
  EXPECT_NEAR(length(sample.direction - expected), 0.0f, 1e-5f);
  EXPECT_EQ(sample.pdf, 0.0f);
  const Vec3 f = fresnelConductor(0.8f, conductorFromReflectance(mirror.specular));
  for (int c = 0; c < 3; ++c) EXPECT_FLOAT_EQ(sample.weight[c], f[c]);
  EXPECT_FALSE(bsdf.hasDiffuse());
  EXPECT_EQ(maxComponent(bsdf.glossy(expected)), 0.0f);   // a direction, not a density
}

TEST(SurfaceBsdf, TheMetalFitGivesItsColourAtNormalIncidenceAndWhitensAtGrazing) {
  const Vec3 copper(0.95f, 0.64f, 0.54f);
  const ConductorIndex index = conductorFromReflectance(copper);
  const Vec3 normal = fresnelConductor(1.0f, index), grazing = fresnelConductor(0.01f, index);
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(normal[c], copper[c], 1e-4f) << c;
    EXPECT_GT(grazing[c], 0.9f) << c;
  }
  EXPECT_NEAR(fresnelDielectric(1.0f, 1.5f), 0.04f, 1e-6f);
}

}  // namespace
}  // namespace portico
