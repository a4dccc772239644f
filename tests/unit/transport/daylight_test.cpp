// The sky model, thin glass and daylight openings, each against figures
// worked out by hand or published.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "common/transport/daylight_openings.h"
#include "common/transport/sampling.h"
#include "common/transport/sky_model.h"
#include "common/transport/sun_disc.h"
#include "common/transport/thin_glass.h"

namespace portico {
namespace {

constexpr float kEfficacy = 179.0f;   // lm/W, the sky's luminance convention

DaylightSettings sky(DaylightSettings::Sky kind, float azimuth = 0, float elevation = 45, float turbidity = 3) {
  DaylightSettings d;
  d.sky = kind;
  d.sun = kind == DaylightSettings::Sky::Preetham;
  d.sunAzimuthDegrees = azimuth;
  d.sunElevationDegrees = elevation;
  d.turbidity = turbidity;
  return d;
}

TEST(SkyModel, UniformSkyGivesPiTimesItsRadianceOnAnyPlane) {
  DaylightSettings d = sky(DaylightSettings::Sky::Uniform);
  d.skyRadiance = Vec3(0.5f, 1.0f, 2.0f);
  const SkyModel model(d);
  for (const Vec3& n : {Vec3(0, 1, 0), Vec3(1, 0, 0), normalize(Vec3(1, -2, 3))}) {
    const Vec3 e = model.irradianceFacing(n);
    EXPECT_FLOAT_EQ(e.x, 0.5f * kPi);
    EXPECT_FLOAT_EQ(e.z, 2.0f * kPi);
  }
  EXPECT_EQ(model.radiance(Vec3(0, -1, 0)), d.skyRadiance);   // below the horizon too, as Mitsuba's constant
}

TEST(SkyModel, OvercastSkyGivesTenThousandLuxOnTheGroundAndIsThreeTimesBrighterAtTheZenith) {
  const SkyModel model(sky(DaylightSettings::Sky::Overcast));
  const float lux = kEfficacy * luminance(model.irradianceFacing(Vec3(0, 1, 0)));
  EXPECT_NEAR(lux, 10000.0f, 100.0f);   // the 32 x 32 quadrature, within 1 %
  EXPECT_NEAR(luminance(model.radiance(Vec3(0, 1, 0))) / luminance(model.radiance(normalize(Vec3(1, 1e-4f, 0)))), 3.0f,
              1e-3f);
  // The ground below the horizon: albedo 0.2 under 10 000 lx.
  EXPECT_NEAR(kEfficacy * luminance(model.radiance(Vec3(0, -1, 0))), 0.2f * 10000.0f / kPi, 20.0f);
}

TEST(SkyModel, PreethamZenithLuminanceFollowsThePaperAndTheSkyIsSymmetricAboutTheSun) {
  // T = 3, sun 45 degrees up: chi = (4/9 - 3/120)(pi - pi/2), Yz = (4.0453 T
  // - 4.9710) tan chi - 0.2155 T + 2.4192 = 7.32 kcd/m^2.
  const SkyModel model(sky(DaylightSettings::Sky::Preetham, 30, 45, 3));
  EXPECT_NEAR(kEfficacy * luminance(model.radiance(Vec3(0, 1, 0))), 7320.0f, 40.0f);
  // Mirror images about the sun's vertical plane have the same radiance.
  const Vec3 sun = model.sunDirection();
  const Vec3 across = normalize(cross(Vec3(0, 1, 0), sun));
  for (float offset : {0.2f, 0.6f, 1.2f}) {
    const Vec3 a = model.radiance(normalize(Vec3(sun.x, 0.3f, sun.z) + across * offset));
    const Vec3 b = model.radiance(normalize(Vec3(sun.x, 0.3f, sun.z) - across * offset));
    EXPECT_NEAR(a.x, b.x, 1e-3f * a.x);
    EXPECT_NEAR(a.z, b.z, 1e-3f * a.z);
  }
  // Brighter round the sun than at right angles to it; bluer overhead than near the sun.
  EXPECT_GT(luminance(model.radiance(normalize(sun + Vec3(0, 0.05f, 0)))), 3 * luminance(model.radiance(across)));
  const Vec3 zenith = model.radiance(Vec3(0, 1, 0));
  EXPECT_GT(zenith.z, zenith.x);
  // A clear sky's diffuse light on the ground: some 10 000 to 30 000 lx.
  const float lux = kEfficacy * luminance(model.irradianceFacing(Vec3(0, 1, 0)));
  EXPECT_GT(lux, 8000.0f);
  EXPECT_LT(lux, 30000.0f);
}

TEST(SkyModel, SunIsDimmerAndRedderNearTheHorizon) {
  const Vec3 high = modelledSunIrradiance(60, 3), low = modelledSunIrradiance(5, 3);
  // Direct normal illuminance of a clear high sun: 80 000 to 110 000 lx.
  EXPECT_GT(kEfficacy * luminance(high), 80000.0f);
  EXPECT_LT(kEfficacy * luminance(high), 110000.0f);
  EXPECT_LT(luminance(low), 0.6f * luminance(high));
  EXPECT_GT(low.x / low.z, high.x / high.z);
  // Azimuth 0 is +Z, 90 is +X; elevation is above the horizontal (+Y up).
  const Vec3 north = sunDirection(0, 0), east = sunDirection(90, 0), up = sunDirection(0, 90);
  EXPECT_NEAR(north.z, 1, 1e-6f);
  EXPECT_NEAR(east.x, 1, 1e-6f);
  EXPECT_NEAR(up.y, 1, 1e-6f);
}

TEST(SkyModel, BadSettingsNameTheirOption) {
  DaylightSettings d;
  d.sun = true;
  d.sunAzimuthDegrees = 400;
  d.sunElevationDegrees = 30;
  EXPECT_NE(daylightProblem(d).find("--sun"), std::string::npos);
  d.sunAzimuthDegrees = 10;
  d.sunElevationDegrees = -5;
  EXPECT_NE(daylightProblem(d).find("elevation -5"), std::string::npos);
  d.sunElevationDegrees = 30;
  EXPECT_EQ(daylightProblem(d), "");
  DaylightSettings clear;
  clear.sky = DaylightSettings::Sky::Preetham;
  EXPECT_NE(daylightProblem(clear).find("--sky preetham needs --sun"), std::string::npos);
}

TEST(ThinGlass, ReflectsFourPercentPerFaceAtNormalIncidenceAndNeverMakesLight) {
  EXPECT_NEAR(fresnelDielectric(1.0f, 1.5f), 0.04f, 1e-6f);
  Material glass;
  glass.transmittance = Vec3(1.0f);
  const GlassResponse normal = thinGlass(glass, -1.0f);
  EXPECT_NEAR(normal.reflectance, 2 * 0.04f / 1.04f, 1e-6f);   // both faces, summed
  for (float c = 0.0f; c <= 1.0f; c += 0.01f) {
    const GlassResponse r = thinGlass(glass, c);
    EXPECT_NEAR(r.reflectance + r.transmittance.x, 1.0f, 1e-6f) << c;   // clear glass loses nothing
    glass.transmittance = Vec3(0.7f, 0.8f, 0.9f);
    const GlassResponse tinted = thinGlass(glass, c);
    EXPECT_LE(tinted.reflectance + maxComponent(tinted.transmittance), 1.0f) << c;
    glass.transmittance = Vec3(1.0f);
  }
  EXPECT_NEAR(thinGlass(glass, 0.0f).reflectance, 1.0f, 1e-6f);   // grazing: a mirror
  EXPECT_GT(thinGlass(glass, 0.2f).reflectance, normal.reflectance);
}

TEST(DaylightOpenings, OutdoorCellsAreKnownByName) {
  EXPECT_TRUE(isOutdoorCell("sky"));
  EXPECT_TRUE(isOutdoorCell("outside"));
  EXPECT_TRUE(isOutdoorCell("facade-3"));
  EXPECT_TRUE(isOutdoorCell("outside-courtyard"));
  EXPECT_FALSE(isOutdoorCell("skylight-room"));
  EXPECT_FALSE(isOutdoorCell("room-1"));
}

TEST(DaylightOpenings, ARayPassesThroughAnOpeningOnlyWithinIt) {
  AreaLight window;   // 1 x 1 m in the plane x = 4, facing -x (indoors)
  window.corner = Vec3(4, 1, 0);
  window.edge1 = Vec3(0, 0, 1);
  window.edge2 = Vec3(0, 1, 0);
  ASSERT_LT(window.normal().x, 0);
  const auto t = DaylightEmitters::distanceThrough(window, Vec3(1, 1.5f, 0.5f), Vec3(1, 0, 0));
  ASSERT_TRUE(t);
  EXPECT_NEAR(*t, 3.0f, 1e-6f);
  EXPECT_FALSE(DaylightEmitters::distanceThrough(window, Vec3(1, 2.5f, 0.5f), Vec3(1, 0, 0)));
  EXPECT_FALSE(DaylightEmitters::distanceThrough(window, Vec3(1, 1.5f, 0.5f), Vec3(-1, 0, 0)));   // behind
  window.shape = LightShape::Triangle;
  EXPECT_TRUE(DaylightEmitters::distanceThrough(window, Vec3(1, 1.2f, 0.2f), Vec3(1, 0, 0)));
  EXPECT_FALSE(DaylightEmitters::distanceThrough(window, Vec3(1, 1.8f, 0.8f), Vec3(1, 0, 0)));
}

TEST(SunDisc, DirectionsFillTheDiscOfHalfADegreeUniformly) {
  const Vec3 centre = normalize(Vec3(0.3f, 0.6f, -0.5f));
  const double radius = 0.265 * kPi / 180;   // radians
  double widest = 0, innerHalf = 0;
  Vec3 mean(0);
  constexpr int kSamples = 20000;
  for (int i = 0; i < kSamples; ++i) {
    const float u1 = randomUniform(7, RandomStream::Camera, i, 0, dim::DirectionU);
    const Vec3 d = sampleSunDisc(centre, u1, randomUniform(7, RandomStream::Camera, i, 0, dim::DirectionV));
    EXPECT_NEAR(length(d), 1.0f, 1e-6f);
    if (u1 < 0.99f) ASSERT_TRUE(insideSunDisc(d, centre)) << i;   // the rim is a matter of rounding
    const double angle = 2 * std::asin(0.5 * length(d - centre));
    widest = std::max(widest, angle);
    innerHalf += angle < radius / std::sqrt(2.0);   // the inner half of the disc's solid angle
    mean += d;
  }
  EXPECT_GT(widest, 0.99 * radius);
  EXPECT_LT(widest, 1.001 * radius);
  EXPECT_NEAR(innerHalf / kSamples, 0.5, 0.02);   // uniform over the solid angle
  EXPECT_GT(dot(normalize(mean), centre), 1.0f - 1e-6f);
  // A direction a degree away is outside; the solid angle is pi r^2.
  EXPECT_FALSE(insideSunDisc(normalize(centre + Vec3(0.0175f, 0, 0)), centre));
  EXPECT_NEAR(kSunDiscSolidAngle, kPi * radius * radius, 1e-3 * kSunDiscSolidAngle);
}

}  // namespace
}  // namespace portico
