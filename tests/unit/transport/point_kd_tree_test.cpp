#include "common/transport/point_kd_tree.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "common/rng.h"

namespace portico {
namespace {

float uniform(uint64_t seed, uint64_t i) { return randomUniform(seed, RandomStream::Light, i, 0, 0); }

std::vector<Vec3> randomPoints(uint32_t count, uint64_t seed) {
  std::vector<Vec3> points;
  for (uint32_t i = 0; i < count; ++i) points.push_back({uniform(seed, 3 * i), uniform(seed, 3 * i + 1), uniform(seed, 3 * i + 2)});
  return points;
}

// Brute force over the tree's slots, with the same float distance.
std::vector<uint64_t> bruteWithin(const PointKdTree& tree, const Vec3& p, float radiusSquared, uint32_t rejectEvery) {
  std::vector<uint64_t> keys;
  for (uint32_t slot = 0; slot < tree.size(); ++slot) {
    const Vec3 offset = tree.position(slot) - p;
    const float distanceSquared = dot(offset, offset);
    if (distanceSquared <= radiusSquared && slot % rejectEvery != 0)
      keys.push_back(PointKdTree::candidateKey(distanceSquared, slot));
  }
  std::sort(keys.begin(), keys.end());
  return keys;
}

void expectWithinMatchesBruteForce(const std::vector<Vec3>& points, uint64_t seed) {
  const PointKdTree tree(points);
  ASSERT_EQ(tree.size(), points.size());
  // Slots renumber the points: order() is a permutation, and each slot
  // holds its point.
  std::vector<uint32_t> seen(points.size(), 0);
  for (uint32_t slot = 0; slot < tree.size(); ++slot) {
    ASSERT_EQ(tree.position(slot), points[tree.order()[slot]]);
    ++seen[tree.order()[slot]];
  }
  EXPECT_TRUE(std::all_of(seen.begin(), seen.end(), [](uint32_t n) { return n == 1; }));
  std::vector<uint64_t> keys;
  for (uint64_t q = 0; q < 100; ++q) {
    const Vec3 p = q % 4 == 0 ? points[q % points.size()]
                              : Vec3(uniform(seed, 3 * q) * 1.4f - 0.2f, uniform(seed, 3 * q + 1) * 1.4f - 0.2f,
                                     uniform(seed, 3 * q + 2) * 1.4f - 0.2f);
    for (float radius : {0.0f, 0.01f, 0.1f, 0.5f, kInfinity}) {
      for (uint32_t rejectEvery : {1000000000u, 3u}) {
        keys.clear();
        tree.within(p, radius * radius, [&](uint32_t slot) { return slot % rejectEvery != 0; }, keys);
        std::sort(keys.begin(), keys.end());
        ASSERT_EQ(keys, bruteWithin(tree, p, radius * radius, rejectEvery)) << q << " radius " << radius;
      }
    }
  }
}

TEST(PointKdTree, WithinMatchesBruteForceInACube) { expectWithinMatchesBruteForce(randomPoints(5000, 1), 2); }

TEST(PointKdTree, WithinMatchesBruteForceOnAPlaneAndWithDuplicates) {
  std::vector<Vec3> points;
  for (const Vec3& p : randomPoints(3000, 3)) points.push_back({p.x, 0.5f, p.z});
  for (int copies = 0; copies < 3; ++copies)
    for (uint32_t i = 0; i < 500; ++i) points.push_back(points[i]);
  for (uint32_t i = 0; i < 100; ++i) points.push_back({0.25f, 0.25f, 0.25f});   // one point, 100 times
  expectWithinMatchesBruteForce(points, 4);
}

TEST(PointKdTree, EverySmallSize) {
  for (uint32_t count = 1; count <= 70; ++count) expectWithinMatchesBruteForce(randomPoints(count, 10 + count), count);
}

TEST(PointKdTree, AllPointsEqual) {
  const std::vector<Vec3> points(1000, Vec3(0.5f, 0.5f, 0.5f));
  const PointKdTree tree(points);
  uint64_t heap[2000];
  // Every point ties: the k nearest are the k lowest slots.
  const uint32_t found = tree.search({0.5f, 0.5f, 0.6f}, 10, kInfinity, [](uint32_t) { return true; }, heap);
  ASSERT_EQ(found, 10u);
  std::sort_heap(heap, heap + found);
  for (uint32_t i = 0; i < found; ++i) EXPECT_EQ(PointKdTree::candidateSlot(heap[i]), i);
  // k above the count finds them all.
  EXPECT_EQ(tree.search({0, 0, 0}, 1500, kInfinity, [](uint32_t) { return true; }, heap), 1000u);
}

TEST(PointKdTree, ForgettingTheOrderKeepsTheTree) {
  PointKdTree tree(randomPoints(100, 5));
  const Vec3 first = tree.position(0);
  tree.forgetOrder();
  EXPECT_TRUE(tree.order().empty());
  EXPECT_EQ(tree.size(), 100u);
  EXPECT_EQ(tree.position(0), first);
  std::vector<uint64_t> keys;
  tree.within({0.5f, 0.5f, 0.5f}, kInfinity, [](uint32_t) { return true; }, keys);
  EXPECT_EQ(keys.size(), 100u);
}

TEST(PointKdTree, EmptyTreeFindsNothing) {
  const PointKdTree tree(std::vector<Vec3>{});
  uint64_t heap[4];
  EXPECT_EQ(tree.size(), 0u);
  EXPECT_EQ(tree.search({0, 0, 0}, 4, kInfinity, [](uint32_t) { return true; }, heap), 0u);
  std::vector<uint64_t> keys;
  tree.within({0, 0, 0}, kInfinity, [](uint32_t) { return true; }, keys);
  EXPECT_TRUE(keys.empty());
}

}  // namespace
}  // namespace portico
