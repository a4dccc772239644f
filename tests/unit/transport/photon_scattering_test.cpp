#include "common/transport/photon_scattering.h"

#include <gtest/gtest.h>

#include <cmath>

namespace portico {
namespace {

// The unit square of the plane y = 0; its triangles' geometric normal is +y.
const float kPositions[] = {0, 0, 0, 1, 0, 0, 1, 0, 1, 0, 0, 1};
const uint32_t kIndices[] = {0, 2, 1, 0, 3, 2};
const MeshView kFloor{kPositions, 4, kIndices, 2, 0};

Material material(float albedo, float emission = 0) {
  Material m;
  m.albedo = Vec3(albedo);
  m.emission = Vec3(emission);
  return m;
}

// A photon at height `height` above the floor's middle, heading straight at it.
RayState photonAt(float height, uint64_t path = 7) {
  RayState photon;
  photon.pathId = path;
  photon.origin = {0.5f, height, 0.5f};
  photon.direction = {0, height > 0 ? -1.0f : 1.0f, 0};
  photon.weight = {2, 3, 4};
  return photon;
}

TEST(PhotonScattering, EmittersAndBlackSurfacesAbsorbWithoutADeposit) {
  for (const Material& m : {material(0.8f, 5.0f), material(0.0f)}) {
    RayState photon = photonAt(1);
    const RayState before = photon;
    const PhotonScatter scatter = scatterPhoton(photon, {kFloor, 0, 1.0f, 0.25f, 0.25f, m}, 1, 64);
    EXPECT_FALSE(scatter.deposited);
    EXPECT_FALSE(scatter.bounced);
    EXPECT_EQ(photon.origin, before.origin);
    EXPECT_EQ(photon.depth, 0);
  }
}

TEST(PhotonScattering, DepositsIntoTheLitSideAndBouncesOffIt) {
  for (float height : {1.0f, -1.0f}) {   // from above, then from below (the back side)
    const float side = height > 0 ? 1.0f : -1.0f;
    RayState photon = photonAt(height);
    const PhotonScatter scatter = scatterPhoton(photon, {kFloor, 1, std::abs(height), 0.0f, 0.5f, material(1.0f)}, 1, 64);
    ASSERT_TRUE(scatter.deposited);
    // (0.5, 0, 0.5) lies on the triangle's edge: the deposit is a hair inside.
    EXPECT_NEAR(scatter.deposit.position.x, 0.5f, 1e-4f);
    EXPECT_EQ(scatter.deposit.position.y, 0.0f);
    EXPECT_NEAR(scatter.deposit.position.z, 0.5f, 1e-4f);
    EXPECT_GT(scatter.deposit.position.z, scatter.deposit.position.x);
    EXPECT_EQ(scatter.deposit.direction, Vec3(0, -side, 0));
    EXPECT_EQ(scatter.deposit.power, Vec3(2, 3, 4));
    EXPECT_EQ(scatter.deposit.pathId, 7u);
    EXPECT_EQ(scatter.deposit.bounce, 0);
    // Albedo 1: it always survives, with its power.
    ASSERT_TRUE(scatter.bounced);
    EXPECT_EQ(photon.depth, 1);
    EXPECT_EQ(photon.weight, Vec3(2, 3, 4));
    EXPECT_GT(photon.origin.y * side, 0.0f);
    EXPECT_GT(photon.direction.y * side, 0.0f);
    EXPECT_NEAR(length(photon.direction), 1.0f, 1e-5f);
    EXPECT_EQ(photon.tMin, 0.0f);
    EXPECT_EQ(photon.tMax, kInfinity);
  }
}

TEST(PhotonScattering, TheBounceCapEndsThePathAfterItsDeposit) {
  RayState photon = photonAt(1);
  photon.depth = 3;
  const PhotonScatter scatter = scatterPhoton(photon, {kFloor, 0, 1.0f, 0.25f, 0.25f, material(1.0f)}, 1, 4);
  EXPECT_TRUE(scatter.deposited);
  EXPECT_EQ(scatter.deposit.bounce, 3);
  EXPECT_FALSE(scatter.bounced);
}

TEST(PhotonScattering, RussianRouletteKeepsTheExpectedPower) {
  constexpr int kPaths = 20000;
  int survivors = 0;
  for (uint64_t path = 0; path < kPaths; ++path) {
    RayState photon = photonAt(1, path);
    if (!scatterPhoton(photon, {kFloor, 0, 1.0f, 0.25f, 0.25f, material(0.25f)}, 3, 64).bounced) continue;
    ++survivors;
    EXPECT_EQ(photon.weight, Vec3(2, 3, 4));   // power * albedo / survival
  }
  EXPECT_NEAR(double(survivors) / kPaths, 0.25, 0.015);
}

TEST(PhotonScattering, EmissionLeavesTheLitSideOfTheLightWithItsShareOfPower) {
  AreaLight light;
  light.corner = {0, 3, 0};
  light.edge1 = {0, 0, 1};
  light.edge2 = {1, 0, 0};   // normal cross(edge1, edge2) = +y
  const Vec3 power(0.5f);
  for (uint64_t path = 0; path < 100; ++path) {
    const RayState photon = emitPhoton(light, light.normal(), power, 9, path);
    EXPECT_EQ(photon.kind, RayKind::Photon);
    EXPECT_EQ(photon.pathId, path);
    EXPECT_EQ(photon.depth, 0);
    EXPECT_EQ(photon.weight, power);
    EXPECT_GT(photon.origin.y, 3.0f);
    EXPECT_LT(photon.origin.y, 3.001f);
    EXPECT_GE(photon.origin.x, 0.0f);
    EXPECT_LE(photon.origin.x, 1.0f);
    EXPECT_GT(photon.direction.y, 0.0f);
    const RayState again = emitPhoton(light, light.normal(), power, 9, path);
    EXPECT_EQ(again.direction, photon.direction);   // counter-based: the path decides
  }
}

}  // namespace
}  // namespace portico
