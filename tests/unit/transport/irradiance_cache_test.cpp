#include "common/transport/irradiance_cache.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "common/rng.h"

namespace portico {
namespace {

float uniform(uint64_t seed, uint64_t i, uint32_t dimension) {
  return randomUniform(seed, RandomStream::Light, i, 0, dimension);
}

// `count` photons of power 1 spread uniformly over the unit square of the
// plane `height` (y), lit from above: direction into the surface is -y.
std::vector<StoredPhoton> floorPhotons(uint32_t count, float height, uint64_t seed, uint64_t firstPath = 0) {
  std::vector<StoredPhoton> photons;
  for (uint32_t i = 0; i < count; ++i)
    photons.push_back({{uniform(seed, i, 0), height, uniform(seed, i, 1)}, {0, -1, 0}, {1, 1, 1}, firstPath + i, 1});
  return photons;
}

TEST(IrradianceCache, HoldsAPointAtAboutOnePhotonInStrideWithTheOthersEstimateThere) {
  const PhotonMap map(floorPhotons(10000, 0.0f, 3));
  const IrradianceCache cache(map, 4, 64, 0.5f);
  std::vector<uint8_t> points(map.size());
  for (uint32_t i = 0; i < map.size(); ++i) points[i] = IrradianceCache::isPoint(i, 4);
  const size_t picked = size_t(std::count(points.begin(), points.end(), 1));
  EXPECT_EQ(cache.size(), picked);
  EXPECT_NEAR(double(picked), 2500.0, 150.0);
  // A lookup exactly at a point returns the estimate over the photons that
  // are not points, scaled by 4/3, bit for bit.
  for (uint32_t i = 0; i < map.size(); i += 97) {
    if (!points[i]) continue;
    Vec3 value;
    ASSERT_TRUE(cache.lookup(map.photon(i).position, {0, 1, 0}, value));
    EXPECT_EQ(value, map.radiance(map.photon(i).position, {0, 1, 0}, Vec3(4.0f / 3.0f), 64, 0.5f, &points));
  }
}

TEST(IrradianceCache, GivesTheRadiusOfThePointsEstimateTheDistanceOfItsKthPhoton) {
  // The radius a gather hit's distance is measured against (short gather
  // rays, cell_kernel.h): that of the k photons the point's estimate used.
  const PhotonMap map(floorPhotons(10000, 0.0f, 7));
  const IrradianceCache cache(map, 4, 32, 0.5f);
  std::vector<uint8_t> points(map.size());
  for (uint32_t i = 0; i < map.size(); ++i) points[i] = IrradianceCache::isPoint(i, 4);
  size_t checked = 0;
  for (uint32_t i = 0; i < map.size(); i += 31) {
    if (!points[i]) continue;
    Vec3 value;
    float radius = 0;
    ASSERT_TRUE(cache.lookup(map.photon(i).position, {0, 1, 0}, value, &radius));
    // The 32nd nearest photon that is not a point (all face the query).
    std::vector<uint32_t> nearest;
    map.nearest(map.photon(i).position, 200, 0.5f, nearest);
    uint32_t kept = 0;
    float kth = 0;
    for (uint32_t photon : nearest)
      if (!points[photon] && ++kept == 32) {
        kth = length(map.photon(photon).position - map.photon(i).position);
        break;
      }
    ASSERT_EQ(kept, 32u);
    EXPECT_NEAR(radius, kth, 1e-5f);
    ++checked;
  }
  EXPECT_GT(checked, 50u);
  // On 1 m^2 with 7 500 photons that are not points, 32 lie within about
  // sqrt(32 / (7500 pi)) = 3.7 cm.
  Vec3 value;
  float radius = 0;
  ASSERT_TRUE(cache.lookup({0.5f, 0, 0.5f}, {0, 1, 0}, value, &radius));
  EXPECT_NEAR(radius, 0.037f, 0.012f);
}

TEST(IrradianceCache, ReadsTheIrradianceOfAUniformlyLitFloor) {
  // 20 000 photons of power 1 on 1 m^2: E = 20 000 W/m^2, radiance per unit albedo E / pi.
  const PhotonMap map(floorPhotons(20000, 0.0f, 5));
  const IrradianceCache cache(map, 4, 64, 0.5f);
  const float expected = 20000.0f / kPi;
  for (const Vec3 p : {Vec3(0.5f, 0, 0.5f), Vec3(0.3f, 0, 0.6f), Vec3(0.7f, 0, 0.25f)}) {
    Vec3 value;
    ASSERT_TRUE(cache.lookup(p, {0, 1, 0}, value));
    EXPECT_NEAR(value.x, expected, 0.2f * expected) << p.x << ", " << p.z;
  }
}

TEST(IrradianceCache, IsOnAverageWhatTheEstimateAtAnyPointReads) {
  // Estimated from the photons the points are drawn from, lookups would
  // read 2 % low at k 64 and 4 % at k 16 (see irradiance_cache.h): averaged
  // over the floor's interior the cache agrees with the estimate it stands
  // in for, taken at the same points, within 1 %.
  const PhotonMap map(floorPhotons(40000, 0.0f, 19));
  for (const uint32_t k : {16u, 64u}) {
    const IrradianceCache cache(map, 4, k, 0.5f);
    double cached = 0, estimated = 0;
    const int queries = 4000;
    for (int i = 0; i < queries; ++i) {
      const Vec3 p(0.2f + 0.6f * uniform(23, i, 0), 0.0f, 0.2f + 0.6f * uniform(23, i, 1));
      Vec3 value;
      ASSERT_TRUE(cache.lookup(p, {0, 1, 0}, value));
      cached += value.x;
      estimated += map.radiance(p, {0, 1, 0}, Vec3(1.0f), k, 0.5f).x;
    }
    EXPECT_NEAR(cached / estimated, 1.0, 0.01) << "k " << k;
    EXPECT_NEAR(cached / queries, 40000.0 / kPi, 0.03 * 40000.0 / kPi) << "k " << k;
  }
}

TEST(IrradianceCache, UsesOnlyPointsOnSurfacesFacingTheHitsWay) {
  // The floor y = 0 lit from above, and a wall x = 0.5 lit from -x (its
  // photons go +x into it): a floor hit beside the wall reads the floor, a
  // hit on the wall's lit side the wall, its back side nothing.
  std::vector<StoredPhoton> photons = floorPhotons(4000, 0.0f, 7);
  for (uint32_t i = 0; i < 4000; ++i)
    photons.push_back({{0.5f, uniform(9, i, 0), uniform(9, i, 1)}, {1, 0, 0}, {5, 5, 5}, 100000 + i, 1});
  const PhotonMap map(std::move(photons));
  const IrradianceCache cache(map, 2, 32, 0.5f);
  Vec3 onFloor, onWall, behindWall;
  ASSERT_TRUE(cache.lookup({0.49f, 0.0f, 0.5f}, {0, 1, 0}, onFloor));
  ASSERT_TRUE(cache.lookup({0.5f, 0.5f, 0.5f}, {-1, 0, 0}, onWall));
  EXPECT_FALSE(cache.lookup({0.5f, 0.5f, 0.5f}, {1, 0, 0}, behindWall));
  // Wall photons carry five times the power: the two values are far apart.
  EXPECT_GT(onWall.x, 2.5f * onFloor.x);
}

TEST(IrradianceCache, ARaisedSurfaceDoesNotStandInForTheFloorBelow) {
  // Only a box top at y = 0.3, facing up: a floor hit under it finds no point.
  const PhotonMap map(floorPhotons(2000, 0.3f, 11));
  const IrradianceCache cache(map, 2, 16, 0.5f);
  Vec3 value;
  EXPECT_FALSE(cache.lookup({0.5f, 0.0f, 0.5f}, {0, 1, 0}, value));
  EXPECT_TRUE(cache.lookup({0.5f, 0.3f, 0.5f}, {0, 1, 0}, value));
}

TEST(IrradianceCache, DoesNotDependOnTheOrderPhotonsArrivedIn) {
  std::vector<StoredPhoton> photons = floorPhotons(5000, 0.0f, 13);
  std::vector<StoredPhoton> reversed(photons.rbegin(), photons.rend());
  const PhotonMap a(std::move(photons)), b(std::move(reversed));
  const IrradianceCache first(a, 3, 32, 0.5f), second(b, 3, 32, 0.5f);
  for (uint32_t i = 0; i < 200; ++i) {
    const Vec3 p(uniform(17, i, 0), 0.0f, uniform(17, i, 1));
    Vec3 x, y;
    ASSERT_TRUE(first.lookup(p, {0, 1, 0}, x));
    ASSERT_TRUE(second.lookup(p, {0, 1, 0}, y));
    EXPECT_EQ(x, y);
  }
}

TEST(IrradianceCache, AnEmptyMapHasNoPointsAndAStrideUnderTwoIsRefused) {
  const PhotonMap empty(std::vector<StoredPhoton>{});
  const IrradianceCache cache(empty, 4, 64, 0.5f);
  Vec3 value;
  EXPECT_EQ(cache.size(), 0u);
  EXPECT_FALSE(cache.lookup({0, 0, 0}, {0, 1, 0}, value));
  EXPECT_THROW(IrradianceCache(empty, 1, 64, 0.5f), std::invalid_argument);
}

}  // namespace
}  // namespace portico
