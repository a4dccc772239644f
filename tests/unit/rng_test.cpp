#include "common/rng.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <vector>

namespace portico {
namespace {

TEST(Random, IsAPureFunctionOfItsKey) {
  for (uint64_t path = 0; path < 100; ++path)
    EXPECT_EQ(randomBits(7, RandomStream::Photon, path, 3, 2), randomBits(7, RandomStream::Photon, path, 3, 2));
}

TEST(Random, EveryKeyPartChangesTheValue) {
  const uint64_t base = randomBits(1, RandomStream::Photon, 10, 2, 3);
  EXPECT_NE(base, randomBits(2, RandomStream::Photon, 10, 2, 3));
  EXPECT_NE(base, randomBits(1, RandomStream::Camera, 10, 2, 3));
  EXPECT_NE(base, randomBits(1, RandomStream::Photon, 11, 2, 3));
  EXPECT_NE(base, randomBits(1, RandomStream::Photon, 10, 3, 3));
  EXPECT_NE(base, randomBits(1, RandomStream::Photon, 10, 2, 4));
}

TEST(Random, UniformStaysInUnitInterval) {
  for (uint64_t path = 0; path < 100000; ++path) {
    const float u = randomUniform(3, RandomStream::Camera, path, 0, 0);
    ASSERT_GE(u, 0.0f);
    ASSERT_LT(u, 1.0f);
  }
}

// Chi-square over 64 bins for consecutive path ids, the pattern the renderer uses.
double chiSquare(const std::vector<float>& samples, int bins) {
  std::vector<int> counts(bins, 0);
  for (float u : samples) counts[static_cast<int>(u * bins)]++;
  const double expected = double(samples.size()) / bins;
  double chi = 0;
  for (int c : counts) chi += (c - expected) * (c - expected) / expected;
  return chi;
}

TEST(Random, ConsecutivePathsAreUniform) {
  std::vector<float> samples;
  for (uint64_t path = 0; path < 200000; ++path) samples.push_back(randomUniform(42, RandomStream::Photon, path, 0, 0));
  // 63 degrees of freedom: the 99.99th percentile is about 117.
  EXPECT_LT(chiSquare(samples, 64), 117.0);
}

TEST(Random, ConsecutiveDimensionsAndBouncesAreUniform) {
  std::vector<float> byDimension, byBounce;
  for (uint32_t k = 0; k < 200000; ++k) {
    byDimension.push_back(randomUniform(5, RandomStream::Photon, 17, 0, k));
    byBounce.push_back(randomUniform(5, RandomStream::Photon, 17, k, 0));
  }
  EXPECT_LT(chiSquare(byDimension, 64), 117.0);
  EXPECT_LT(chiSquare(byBounce, 64), 117.0);
}

TEST(Random, DimensionsAreUncorrelated) {
  // Pairs (u, v) from two dimensions of the same path fill the unit square
  // evenly: 16x16 cells, chi-square with 255 degrees of freedom (99.99%: ~360).
  const int n = 256000;
  std::vector<int> counts(256, 0);
  for (uint64_t path = 0; path < n; ++path) {
    const float u = randomUniform(9, RandomStream::Photon, path, 1, dim::DirectionU);
    const float v = randomUniform(9, RandomStream::Photon, path, 1, dim::DirectionV);
    counts[int(u * 16) * 16 + int(v * 16)]++;
  }
  const double expected = n / 256.0;
  double chi = 0;
  for (int c : counts) chi += (c - expected) * (c - expected) / expected;
  EXPECT_LT(chi, 360.0);
}

TEST(Random, FewCollisionsAcrossStreams) {
  std::set<uint64_t> seen;
  for (uint64_t path = 0; path < 10000; ++path) {
    seen.insert(randomBits(1, RandomStream::Photon, path, 0, 0));
    seen.insert(randomBits(1, RandomStream::Camera, path, 0, 0));
  }
  EXPECT_EQ(seen.size(), 20000u);
}

}  // namespace
}  // namespace portico
