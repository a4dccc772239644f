#include "common/accel/bvh_build.h"

#include <gtest/gtest.h>

#include <cstring>
#include <random>

#include "common/accel/bvh_node.h"
#include "tests/unit/accel/accel_test_scenes.h"

namespace portico {
namespace {

using accel_test::TestMesh;

template <int Width>
BvhData<Width> buildWith(const TestMesh& mesh, bool avx) {
  useBvhAvxBinning(avx);
  BvhData<Width> tree = buildBvh<Width>(mesh.view());
  useBvhAvxBinning(true);
  return tree;
}

template <int Width>
void expectSameTree(const BvhData<Width>& a, const BvhData<Width>& b) {
  ASSERT_EQ(a.nodes.size(), b.nodes.size());
  ASSERT_EQ(a.packets.size(), b.packets.size());
  // Field by field: a node's tail past its child words is padding.
  size_t differentNodes = 0;
  for (size_t n = 0; n < a.nodes.size(); ++n)
    differentNodes += std::memcmp(a.nodes[n].box, b.nodes[n].box, sizeof(a.nodes[n].box)) != 0 ||
                      std::memcmp(a.nodes[n].child, b.nodes[n].child, sizeof(a.nodes[n].child)) != 0;
  EXPECT_EQ(differentNodes, 0u);
  EXPECT_EQ(0, std::memcmp(a.packets.data(), b.packets.data(), a.packets.size() * sizeof(a.packets[0])));
  EXPECT_EQ(a.leaves, b.leaves);
  EXPECT_EQ(a.triangles, b.triangles);
  EXPECT_EQ(a.maxDepth, b.maxDepth);
}

TEST(BvhBuild, AvxAndSseBinningBuildTheSameTreeBitForBit) {
  useBvhAvxBinning(true);
  if (!bvhAvxBinningInUse()) GTEST_SKIP() << "no AVX on this processor: one binning loop only";
  // A furnished hall large enough for sampled and two-set binning, and a
  // mixed scene with degenerate, duplicate and non-finite triangles.
  TestMesh mixed = accel_test::mixedScene(7);
  std::mt19937 random(7);
  accel_test::addDegenerateAndDuplicates(mixed, 50, random);
  accel_test::poisonSomeTriangles(mixed);
  for (const TestMesh& mesh : {accel_test::furnishedHall(20000, 3), mixed}) {
    expectSameTree(buildWith<8>(mesh, true), buildWith<8>(mesh, false));
    expectSameTree(buildWith<4>(mesh, true), buildWith<4>(mesh, false));
  }
}

TEST(BvhBuild, AvxBinningCanBeTurnedOffAndOn) {
  useBvhAvxBinning(false);
  EXPECT_FALSE(bvhAvxBinningInUse());
  useBvhAvxBinning(true);
  EXPECT_EQ(bvhAvxBinningInUse(), __builtin_cpu_supports("avx") != 0);
}

}  // namespace
}  // namespace portico
