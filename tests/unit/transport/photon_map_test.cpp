#include "common/transport/photon_map.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>
#include <vector>

#include "common/rng.h"

namespace portico {
namespace {

// Deterministic uniform numbers for test data (no std distributions: their
// output differs between standard libraries).
class Uniform {
 public:
  explicit Uniform(uint64_t seed) : seed_(seed) {}
  float next() { return randomUniform(seed_, RandomStream::Light, counter_++, 0, 0); }
  float next(float lo, float hi) { return lo + (hi - lo) * next(); }
  uint32_t below(uint32_t n) { return std::min(n - 1, static_cast<uint32_t>(next() * n)); }

 private:
  uint64_t seed_;
  uint64_t counter_ = 0;
};

StoredPhoton makePhoton(const Vec3& position, uint64_t pathId, uint16_t bounce = 0,
                        const Vec3& direction = {0, -1, 0}, const Vec3& power = {1, 1, 1}) {
  return {position, direction, power, pathId, bounce};
}

std::vector<StoredPhoton> uniformCube(uint32_t count, uint64_t seed) {
  Uniform u(seed);
  std::vector<StoredPhoton> photons;
  for (uint32_t i = 0; i < count; ++i) photons.push_back(makePhoton({u.next(), u.next(), u.next()}, i, i % 4));
  return photons;
}

std::vector<StoredPhoton> clustered(uint32_t count, uint64_t seed) {
  Uniform u(seed);
  std::vector<Vec3> centres;
  for (int c = 0; c < 12; ++c) centres.push_back({u.next(), u.next(), u.next()});
  std::vector<StoredPhoton> photons;
  for (uint32_t i = 0; i < count; ++i) {
    // Sum of uniforms: a bell around the centre, tight clusters.
    const Vec3 offset(u.next() + u.next() + u.next() - 1.5f, u.next() + u.next() + u.next() - 1.5f,
                      u.next() + u.next() + u.next() - 1.5f);
    photons.push_back(makePhoton(centres[u.below(12)] + offset * 0.01f, 1000 + i));
  }
  return photons;
}

std::vector<StoredPhoton> onPlane(uint32_t count, uint64_t seed) {
  Uniform u(seed);
  std::vector<StoredPhoton> photons;
  for (uint32_t i = 0; i < count; ++i) photons.push_back(makePhoton({u.next(), 0.5f, u.next()}, i / 3, i % 3));
  return photons;
}

// Few distinct positions on a lattice: many exact duplicates and many exactly
// equal distances, so results hinge on the index tie-break.
std::vector<StoredPhoton> duplicates(uint32_t count, uint64_t seed) {
  Uniform u(seed);
  std::vector<StoredPhoton> photons;
  for (uint32_t i = 0; i < count; ++i) {
    const Vec3 position(static_cast<float>(u.below(4)) * 0.25f, static_cast<float>(u.below(4)) * 0.25f,
                        static_cast<float>(u.below(3)) * 0.25f);
    photons.push_back(makePhoton(position, i * 7919 % count, 0));
  }
  return photons;
}

struct Expected {
  std::vector<uint32_t> indices;
  float radiusSquared;
};

// Brute force over photon(i), with the same float distance as the map.
Expected bruteForce(const PhotonMap& map, const Vec3& p, uint32_t k, float maxRadius) {
  const float maxRadiusSquared = maxRadius * maxRadius;
  std::vector<std::pair<float, uint32_t>> all;
  for (uint32_t i = 0; i < map.size(); ++i) {
    const Vec3 offset = map.photon(i).position - p;
    const float distanceSquared = dot(offset, offset);
    if (distanceSquared <= maxRadiusSquared) all.push_back({distanceSquared, i});
  }
  if (all.size() > k) {
    std::nth_element(all.begin(), all.begin() + k, all.end());
    all.resize(k);
  }
  std::sort(all.begin(), all.end());
  Expected expected;
  for (const auto& [d, i] : all) expected.indices.push_back(i);
  expected.radiusSquared = (k > 0 && all.size() == k) ? all.back().first : (k == 0 ? 0.0f : maxRadiusSquared);
  return expected;
}

void expectMatchesBruteForce(const std::vector<StoredPhoton>& photons, uint64_t seed) {
  const PhotonMap map(photons);
  ASSERT_EQ(map.size(), photons.size());
  Uniform u(seed);
  std::vector<uint32_t> out;
  const uint32_t ks[] = {1, 2, 7, 50, 333};
  const float radii[] = {kInfinity, 0.3f, 0.05f, 0.0f};
  for (int q = 0; q < 150; ++q) {
    // Some queries sit exactly on a photon, the rest anywhere around the set.
    const Vec3 p = q % 5 == 0 ? map.photon(u.below(static_cast<uint32_t>(map.size()))).position
                              : Vec3(u.next(-0.2f, 1.2f), u.next(-0.2f, 1.2f), u.next(-0.2f, 1.2f));
    for (uint32_t k : ks) {
      for (float radius : radii) {
        const Expected expected = bruteForce(map, p, k, radius);
        // No guess (a heap of the k nearest), then guessed radii far too
        // small, about right and far too large (a range search, widened).
        for (float guess : {0.0f, 1e-4f, 0.02f, 0.2f, 5.0f}) {
          float radiusGuess = guess;
          const float returned = map.nearest(p, k, radius, out, guess > 0 ? &radiusGuess : nullptr);
          ASSERT_EQ(out, expected.indices) << "query " << q << " k " << k << " radius " << radius << " guess " << guess;
          ASSERT_EQ(returned, expected.radiusSquared) << "query " << q << " k " << k << " radius " << radius;
        }
      }
    }
  }
}

TEST(PhotonMap, NearestMatchesBruteForceInAUniformCube) { expectMatchesBruteForce(uniformCube(20000, 1), 11); }
TEST(PhotonMap, NearestMatchesBruteForceInClusters) { expectMatchesBruteForce(clustered(20000, 2), 12); }
TEST(PhotonMap, NearestMatchesBruteForceOnAPlane) { expectMatchesBruteForce(onPlane(20000, 3), 13); }
TEST(PhotonMap, NearestMatchesBruteForceWithManyDuplicates) { expectMatchesBruteForce(duplicates(5000, 4), 14); }

// Points on one line, and points at distances halving towards one end
// (each midpoint split would take off a single point: the builder falls
// back to median splits).
std::vector<StoredPhoton> onALine(uint32_t count, uint64_t seed) {
  Uniform u(seed);
  std::vector<StoredPhoton> photons;
  for (uint32_t i = 0; i < count; ++i) photons.push_back(makePhoton({u.next(), 0.25f, 0.75f}, i));
  return photons;
}

std::vector<StoredPhoton> halvingDistances(uint32_t count) {
  std::vector<StoredPhoton> photons;
  for (uint32_t i = 0; i < count; ++i) photons.push_back(makePhoton({std::ldexp(1.0f, -int(i % 120)), 0.5f, float(i / 120) * 1e-3f}, i));
  return photons;
}

TEST(PhotonMap, NearestMatchesBruteForceOnALine) { expectMatchesBruteForce(onALine(5000, 15), 16); }
TEST(PhotonMap, NearestMatchesBruteForceAtHalvingDistances) { expectMatchesBruteForce(halvingDistances(3000), 17); }

TEST(PhotonMap, NearestMatchesBruteForceForEverySmallSize) {
  // Every size from a single leaf to a few, k larger than the map.
  for (uint32_t count = 1; count <= 40; ++count) {
    const PhotonMap map(uniformCube(count, 100 + count));
    Uniform u(count);
    std::vector<uint32_t> out;
    for (int q = 0; q < 20; ++q) {
      const Vec3 p(u.next(), u.next(), u.next());
      for (uint32_t k : {1u, 3u, count, count + 5}) {
        float radiusGuess = 0.1f;
        const float returned = map.nearest(p, k, kInfinity, out, q % 2 ? &radiusGuess : nullptr);
        const Expected expected = bruteForce(map, p, k, kInfinity);
        ASSERT_EQ(out, expected.indices) << "count " << count << " k " << k;
        ASSERT_EQ(returned, expected.radiusSquared);
      }
    }
  }
}

TEST(PhotonMap, HoldsEveryPhotonOnce) {
  // The map reorders the photons (the tree's leaf order): the same photons,
  // each once.
  std::vector<StoredPhoton> photons = uniformCube(1000, 5);
  std::reverse(photons.begin(), photons.end());
  const PhotonMap map(photons);
  ASSERT_EQ(map.size(), photons.size());
  std::vector<uint64_t> paths;
  for (size_t i = 0; i < map.size(); ++i) {
    ASSERT_EQ(map.photon(i).position, photons[photons.size() - 1 - map.photon(i).pathId].position) << i;
    paths.push_back(map.photon(i).pathId);
  }
  std::sort(paths.begin(), paths.end());
  for (size_t i = 0; i < paths.size(); ++i) ASSERT_EQ(paths[i], i);
}

void expectSamePhoton(const StoredPhoton& a, const StoredPhoton& b) {
  EXPECT_EQ(a.position, b.position);
  EXPECT_EQ(a.direction, b.direction);
  EXPECT_EQ(a.power, b.power);
  EXPECT_EQ(a.pathId, b.pathId);
  EXPECT_EQ(a.bounce, b.bounce);
}

TEST(PhotonMap, ArrivalOrderDoesNotChangeAnything) {
  // Includes photons sharing (pathId, bounce) and fully identical photons.
  Uniform u(6);
  std::vector<StoredPhoton> photons = clustered(5000, 7);
  for (uint32_t i = 0; i < 3000; ++i) {
    const Vec3 position(u.next(), u.next(), u.next());
    const Vec3 direction = normalize(Vec3(u.next(-1, 1), -1.0f, u.next(-1, 1)));
    const Vec3 power(u.next(), u.next(), u.next());
    photons.push_back(makePhoton(position, u.below(50), static_cast<uint16_t>(u.below(3)), direction, power));
    if (i % 10 == 0) photons.push_back(photons.back());
  }
  std::vector<StoredPhoton> shuffled = photons;
  for (size_t i = shuffled.size() - 1; i > 0; --i) std::swap(shuffled[i], shuffled[u.below(static_cast<uint32_t>(i + 1))]);

  const PhotonMap original(photons);
  const PhotonMap reordered(shuffled);
  ASSERT_EQ(original.size(), reordered.size());
  for (size_t i = 0; i < original.size(); ++i) expectSamePhoton(original.photon(i), reordered.photon(i));

  std::vector<uint32_t> a, b;
  for (int q = 0; q < 300; ++q) {
    const Vec3 p(u.next(), u.next(), u.next());
    const Vec3 n = normalize(Vec3(u.next(-1, 1), u.next(-1, 1), u.next(-1, 1)));
    EXPECT_EQ(original.nearest(p, 40, 0.2f, a), reordered.nearest(p, 40, 0.2f, b));
    EXPECT_EQ(a, b);
    const Vec3 la = original.radiance(p, n, Vec3(0.5f), 40, 0.2f);
    const Vec3 lb = reordered.radiance(p, n, Vec3(0.5f), 40, 0.2f);
    EXPECT_EQ(la, lb);   // bit-identical
  }
}

TEST(PhotonMap, RadianceIsTheSameWithOrWithoutAGuess) {
  // A run of nearby queries passing the radius on, as the irradiance cache
  // does, against each query alone: the same bits, with photons left out
  // and photons facing either way.
  Uniform u(40);
  std::vector<StoredPhoton> photons = clustered(8000, 41);
  for (uint32_t i = 0; i < 12000; ++i) {
    const Vec3 direction = normalize(Vec3(u.next(-0.3f, 0.3f), u.next() < 0.8f ? -1.0f : 1.0f, u.next(-0.3f, 0.3f)));
    photons.push_back(makePhoton({u.next(), u.next(0.0f, 0.05f), u.next()}, 5000 + i, 1, direction,
                                 {u.next(), u.next(), u.next()}));
  }
  const PhotonMap map(std::move(photons));
  std::vector<uint8_t> leftOut(map.size());
  for (size_t i = 0; i < map.size(); ++i) leftOut[i] = u.next() < 0.125f;
  const Vec3 n(0, 1, 0);
  float radiusGuess = 0;
  int lit = 0;
  for (int q = 0; q < 400; ++q) {
    const Vec3 p(0.002f * float(q % 200), 0.01f, 0.3f + 0.2f * float(q / 200) + u.next(0.0f, 0.01f));
    for (uint32_t k : {8u, 64u}) {
      const Vec3 alone = map.radiance(p, n, Vec3(0.7f), k, 0.3f, &leftOut);
      ASSERT_EQ(map.radiance(p, n, Vec3(0.7f), k, 0.3f, &leftOut, &radiusGuess), alone) << q << " k " << k;
      lit += alone.x > 0;
    }
  }
  EXPECT_GT(lit, 700);
}

// A square [0, side]^2 on the plane y = height, lit with total power `total`
// by `count` photons on a jittered grid, all travelling along `direction`.
void addLitSquare(std::vector<StoredPhoton>& photons, uint32_t perSide, float side, float height, float total,
                  const Vec3& direction, uint64_t firstPath, uint64_t seed) {
  Uniform u(seed);
  const float cell = side / static_cast<float>(perSide);
  const Vec3 power(total / static_cast<float>(perSide * perSide));
  for (uint32_t i = 0; i < perSide; ++i)
    for (uint32_t j = 0; j < perSide; ++j)
      photons.push_back(makePhoton({(static_cast<float>(i) + u.next()) * cell, height,
                                    (static_cast<float>(j) + u.next()) * cell},
                                   firstPath + i * perSide + j, 1, direction, power));
}

constexpr float kSide = 10.0f;         // area 100
constexpr float kTotalPower = 1000.0f;
constexpr uint32_t kPerSide = 448;     // ~200K photons
const Vec3 kAlbedo(0.5f, 0.7f, 0.9f);
const Vec3 kUp(0, 1, 0);

Vec3 expectedLitRadiance() { return kAlbedo * (kTotalPower / (kSide * kSide) / kPi); }

// Checks each estimate within `each` and their mean within `mean` (relative).
// The jittered photons keep the per-point noise of k = 100 near 5% at worst
// (purely random ones would reach ~45%); the mean's bias is ~0.1%.
void expectUniformRadiance(const PhotonMap& map, uint32_t k, float maxRadius, float each, float mean) {
  const Vec3 expected = expectedLitRadiance();
  Uniform u(21);
  Vec3 sum;
  const int queries = 200;
  for (int q = 0; q < queries; ++q) {
    const Vec3 p(u.next(1.0f, kSide - 1.0f), 0.0f, u.next(1.0f, kSide - 1.0f));
    const Vec3 l = map.radiance(p, kUp, kAlbedo, k, maxRadius);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(l[c], expected[c], each * expected[c]) << "query " << q;
    sum += l;
  }
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(sum[c] / queries, expected[c], mean * expected[c]);
}

TEST(PhotonMap, RadianceOfAUniformlyLitPlane) {
  std::vector<StoredPhoton> photons;
  addLitSquare(photons, kPerSide, kSide, 0.0f, kTotalPower, {0, -1, 0}, 0, 31);
  const PhotonMap map(std::move(photons));
  expectUniformRadiance(map, 100, 1.0f, 0.08f, 0.01f);
}

TEST(PhotonMap, RadianceIgnoresPhotonsFromBehind) {
  std::vector<StoredPhoton> photons;
  addLitSquare(photons, kPerSide, kSide, 0.0f, kTotalPower, {0, 1, 0}, 0, 32);
  {
    const PhotonMap behindOnly(photons);
    for (float x = 1.0f; x < kSide - 1.0f; x += 0.7f)
      EXPECT_EQ(behindOnly.radiance({x, 0, 5.0f}, kUp, kAlbedo, 100, 1.0f), Vec3(0.0f));
  }
  // With the same light also arriving from the front, the estimate sees only
  // the front half, and photons from behind do not use up k.
  addLitSquare(photons, kPerSide, kSide, 0.0f, kTotalPower, {0, -1, 0}, 1u << 20, 33);
  const PhotonMap mixed(std::move(photons));
  expectUniformRadiance(mixed, 100, 1.0f, 0.08f, 0.01f);
}

TEST(PhotonMap, RadianceIgnoresPhotonsOffTheTangentPlane) {
  // The same light on the plane, plus a brighter layer just under it (the far
  // side of a thin floor, facing the same way): outside the disc, ignored.
  std::vector<StoredPhoton> photons;
  addLitSquare(photons, kPerSide, kSide, 0.0f, kTotalPower, {0, -1, 0}, 0, 34);
  addLitSquare(photons, 100, kSide, -0.1f, 10 * kTotalPower, {0, -1, 0}, 1u << 20, 35);
  const PhotonMap map(std::move(photons));
  expectUniformRadiance(map, 100, 1.0f, 0.08f, 0.01f);
}

TEST(PhotonMap, EmptyMapFindsNothing) {
  const PhotonMap map({});
  EXPECT_EQ(map.size(), 0u);
  std::vector<uint32_t> out{1, 2, 3};
  EXPECT_EQ(map.nearest({0, 0, 0}, 10, 2.0f, out), 4.0f);
  EXPECT_TRUE(out.empty());
  EXPECT_EQ(map.radiance({0, 0, 0}, kUp, kAlbedo, 10, 2.0f), Vec3(0.0f));
  EXPECT_GT(map.bytes(), 0u);
}

TEST(PhotonMap, MaxRadiusIsRespected) {
  const PhotonMap map(uniformCube(20000, 8));
  Uniform u(9);
  std::vector<uint32_t> out;
  for (int q = 0; q < 200; ++q) {
    const Vec3 p(u.next(), u.next(), u.next());
    const float radius = u.next(0.0f, 0.1f);
    const float returned = map.nearest(p, 50, radius, out);
    ASSERT_LE(out.size(), 50u);
    for (uint32_t i : out) {
      const Vec3 offset = map.photon(i).position - p;
      ASSERT_LE(dot(offset, offset), radius * radius);
    }
    if (out.size() < 50) {
      EXPECT_EQ(returned, radius * radius);
    } else {
      const Vec3 offset = map.photon(out.back()).position - p;
      EXPECT_EQ(returned, dot(offset, offset));
      EXPECT_LE(returned, radius * radius);
    }
  }
  // Nothing that close: nothing found, and no light.
  const PhotonMap sparse({makePhoton({0, 0, 0}, 0), makePhoton({1, 0, 0}, 1)});
  EXPECT_EQ(sparse.nearest({0.5f, 0, 0}, 5, 0.4f, out), 0.4f * 0.4f);
  EXPECT_TRUE(out.empty());
  EXPECT_EQ(sparse.radiance({0.5f, 0, 0}, kUp, kAlbedo, 5, 0.4f), Vec3(0.0f));
  // A negative radius finds nothing; k = 0 finds nothing.
  EXPECT_EQ(sparse.nearest({0, 0, 0}, 5, -1.0f, out), 0.0f);
  EXPECT_TRUE(out.empty());
  EXPECT_EQ(sparse.nearest({0, 0, 0}, 0, 1.0f, out), 0.0f);
  EXPECT_TRUE(out.empty());
}

TEST(PhotonMap, RadianceWithFewerThanKPhotonsUsesTheWholeDisc) {
  // k far above what the radius holds: r is maxRadius, and the estimate is
  // still the right density.
  std::vector<StoredPhoton> photons;
  addLitSquare(photons, kPerSide, kSide, 0.0f, kTotalPower, {0, -1, 0}, 0, 36);
  const PhotonMap map(std::move(photons));
  expectUniformRadiance(map, 100000, 0.3f, 0.08f, 0.01f);
}

TEST(PhotonMap, RejectsNonFinitePositions) {
  EXPECT_THROW(PhotonMap({makePhoton({0, std::nanf(""), 0}, 0)}), std::invalid_argument);
  EXPECT_THROW(PhotonMap({makePhoton({kInfinity, 0, 0}, 0)}), std::invalid_argument);
}

TEST(PhotonMap, CountsItsMemory) {
  const PhotonMap map(uniformCube(1000, 10));
  EXPECT_GE(map.bytes(), 1000 * (sizeof(StoredPhoton) + 16));
  EXPECT_LE(map.bytes(), 1000 * (sizeof(StoredPhoton) + 16) + 4096);
}

}  // namespace
}  // namespace portico
