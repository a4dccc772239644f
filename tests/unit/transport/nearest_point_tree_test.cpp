#include "common/transport/nearest_point_tree.h"

#include <gtest/gtest.h>

#include <bit>
#include <vector>

#include "common/rng.h"

namespace portico {
namespace {

float uniform(uint64_t seed, uint64_t i, uint32_t dimension) {
  return randomUniform(seed, RandomStream::Light, i, 0, dimension);
}

// The answer by definition: least (squared distance, number) over every
// accepted point within the radius.
template <typename Accept>
uint32_t bruteForceNearest(const NearestPointTree& tree, const Vec3& p, float maxRadiusSquared, Accept accept) {
  uint64_t best = ~uint64_t{0};
  for (uint32_t i = 0; i < tree.size(); ++i) {
    const Vec3 offset = tree.position(i) - p;
    const float distanceSquared = dot(offset, offset);
    const uint64_t key = (uint64_t{std::bit_cast<uint32_t>(distanceSquared)} << 32) | i;
    if (distanceSquared <= maxRadiusSquared && key < best && accept(i)) best = key;
  }
  return best == ~uint64_t{0} ? NearestPointTree::kNone : static_cast<uint32_t>(best);
}

// Points on the faces of a box and on a grid (exact ties), with a filter
// that rejects about half of them.
std::vector<Vec3> testPoints(uint32_t count, uint64_t seed) {
  std::vector<Vec3> points;
  for (uint32_t i = 0; i < count; ++i) {
    const float u = uniform(seed, i, 0), v = uniform(seed, i, 1);
    switch (i % 4) {
      case 0: points.push_back({u * 4, 0, v * 3}); break;         // floor
      case 1: points.push_back({0, u * 2.5f, v * 3}); break;      // wall
      case 2: points.push_back({u * 4, 2.5f, v * 3}); break;      // ceiling
      default: points.push_back({float(i % 7) * 0.5f, 1.0f, float(i % 5) * 0.5f}); break;   // lattice: ties
    }
  }
  return points;
}

TEST(NearestPointTree, FindsWhatBruteForceFindsWithFiltersRadiiAndTies) {
  for (uint32_t count : {0u, 1u, 7u, 8u, 9u, 100u, 5000u}) {
    const std::vector<Vec3> points = testPoints(count, 11 + count);
    const NearestPointTree tree(points);
    ASSERT_EQ(tree.size(), points.size());
    // Every point is kept, renumbered.
    for (uint32_t i = 0; i < tree.size(); ++i) ASSERT_EQ(tree.position(i), points[tree.order()[i]]);
    const auto everyOther = [&](uint32_t i) { return tree.order()[i] % 2 == 0; };
    const auto all = [](uint32_t) { return true; };
    for (uint32_t q = 0; q < 400; ++q) {
      const Vec3 p(uniform(99, q, 0) * 5 - 0.5f, uniform(99, q, 1) * 3 - 0.25f, uniform(99, q, 2) * 4 - 0.5f);
      for (float radius : {0.05f, 0.3f, 10.0f}) {
        const float r2 = radius * radius;
        ASSERT_EQ(tree.nearest(p, r2, all), bruteForceNearest(tree, p, r2, all)) << count << " " << q;
        ASSERT_EQ(tree.nearest(p, r2, everyOther), bruteForceNearest(tree, p, r2, everyOther)) << count << " " << q;
      }
      // Queries exactly at lattice points meet ties at distance 0.
      if (count > 3) {
        const Vec3 at = points[3];
        ASSERT_EQ(tree.nearest(at, 0.01f, all), bruteForceNearest(tree, at, 0.01f, all));
        ASSERT_EQ(tree.nearest(at, 0.01f, everyOther), bruteForceNearest(tree, at, 0.01f, everyOther));
      }
    }
  }
}

// Queries on the planes the points lie on (a hit on a wall reads points on
// that wall): exact, like any other query.
TEST(NearestPointTree, FindsWhatBruteForceFindsOnThePlanesOfItsPoints) {
  const std::vector<Vec3> points = testPoints(20000, 3);
  const NearestPointTree tree(points);
  const auto all = [](uint32_t) { return true; };
  const auto everyThird = [&](uint32_t i) { return tree.order()[i] % 3 == 0; };
  for (uint32_t q = 0; q < 300; ++q) {
    const float u = uniform(41, q, 0), v = uniform(41, q, 1);
    const Vec3 onPlane[] = {{u * 4, 0, v * 3}, {0, u * 2.5f, v * 3}, {u * 4, 2.5f, v * 3}, {u * 4, 1.0f, v * 3}};
    for (const Vec3& p : onPlane)
      for (float r2 : {0.0004f, 0.04f, 100.0f}) {
        ASSERT_EQ(tree.nearest(p, r2, all), bruteForceNearest(tree, p, r2, all)) << q;
        ASSERT_EQ(tree.nearest(p, r2, everyThird), bruteForceNearest(tree, p, r2, everyThird)) << q;
      }
  }
}

// Many equal coordinates, down to every point at one place: the splits that
// keep equal coordinates together still leave a tree its stack can walk.
TEST(NearestPointTree, FindsWhatBruteForceFindsAmongEqualCoordinates) {
  std::vector<Vec3> stairs, same(3000, Vec3(1, 2, 3));
  // Half the points at x 0, a quarter at x 1, an eighth at x 2, ...
  for (uint32_t i = 0; i < 40000; ++i)
    stairs.push_back({float(std::countr_zero(i + 1)), float(i % 3) * 1e-3f, 0});
  for (const std::vector<Vec3>* points : {&stairs, &same}) {
    const NearestPointTree tree(*points);
    ASSERT_EQ(tree.size(), points->size());
    const auto all = [](uint32_t) { return true; };
    const auto odd = [&](uint32_t i) { return tree.order()[i] % 2 == 1; };
    for (uint32_t q = 0; q < 200; ++q) {
      const Vec3 p = (*points)[(q * 7919) % points->size()] + Vec3(0, uniform(5, q, 0) * 2e-3f, 0);
      for (float r2 : {0.0f, 1e-6f, 4.0f}) {
        ASSERT_EQ(tree.nearest(p, r2, all), bruteForceNearest(tree, p, r2, all)) << q;
        ASSERT_EQ(tree.nearest(p, r2, odd), bruteForceNearest(tree, p, r2, odd)) << q;
      }
    }
  }
}

TEST(NearestPointTree, DependsOnlyOnThePointsAndTheirOrder) {
  const std::vector<Vec3> points = testPoints(3000, 5);
  const NearestPointTree a(points), b(points);
  ASSERT_EQ(a.order(), b.order());
  const auto all = [](uint32_t) { return true; };
  for (uint32_t q = 0; q < 100; ++q) {
    const Vec3 p(uniform(7, q, 0) * 4, uniform(7, q, 1) * 2.5f, uniform(7, q, 2) * 3);
    EXPECT_EQ(a.nearest(p, 1.0f, all), b.nearest(p, 1.0f, all));
  }
}

}  // namespace
}  // namespace portico
