#include "common/accel/bvh_build.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>

#include "common/accel/bvh_node.h"
#include "common/accel/bvh_sah_cost.h"
#include "common/accel/triangle_intersect.h"
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

// Every held triangle in exactly one leaf, its packet lanes holding its
// vertices bit for bit and its leaf's box holding them.
template <int Width>
void expectEveryTriangleOnce(const TestMesh& mesh, const BvhData<Width>& tree) {
  std::vector<int> seen(mesh.triangleCount(), 0);
  const auto visitLeaf = [&](uint32_t child, const float (&lo)[3], const float (&hi)[3]) {
    std::vector<uint32_t> primitives;
    for (uint32_t p = 0; p < bvh_child::packetCount(child); ++p) {
      const auto& packet = tree.packets[bvh_child::firstPacket(child) + p];
      for (int lane = 0; lane < 4; ++lane) {
        const uint32_t primitive = packet.primitive[lane];
        ASSERT_LT(primitive, mesh.triangleCount());
        if (std::find(primitives.begin(), primitives.end(), primitive) != primitives.end()) continue;
        primitives.push_back(primitive);
        ++seen[primitive];
        for (int vertex = 0; vertex < 3; ++vertex) {
          const Vec3 v = mesh.vertex(mesh.indices[3 * primitive + vertex]);
          for (int axis = 0; axis < 3; ++axis) {
            EXPECT_EQ(packet.v[vertex][axis][lane], v[axis]);
            EXPECT_TRUE(lo[axis] <= v[axis] && v[axis] <= hi[axis]);
          }
        }
      }
    }
  };
  for (const BvhNode<Width>& node : tree.nodes)
    for (int k = 0; k < Width; ++k) {
      if (!(node.box[0][0][k] <= node.box[0][1][k])) continue;   // an unused slot
      if (!bvh_child::isLeaf(node.child[k])) continue;
      const float lo[3] = {node.box[0][0][k], node.box[1][0][k], node.box[2][0][k]};
      const float hi[3] = {node.box[0][1][k], node.box[1][1][k], node.box[2][1][k]};
      visitLeaf(node.child[k], lo, hi);
    }
  uint64_t held = 0;
  for (size_t t = 0; t < mesh.triangleCount(); ++t) {
    const uint32_t* v = &mesh.indices[3 * t];
    const Vec3 a = mesh.vertex(v[0]), b = mesh.vertex(v[1]), c = mesh.vertex(v[2]);
    const bool finite = std::isfinite(a.x + a.y + a.z + b.x + b.y + b.z + c.x + c.y + c.z);
    const bool heldOne = finite && !isDegenerateTriangle(a, b, c);
    EXPECT_EQ(seen[t], heldOne ? 1 : 0) << t;
    held += heldOne;
  }
  EXPECT_EQ(tree.triangles, held);
}

TEST(BvhBuild, HoldsEveryTriangleOnceThroughEverySplitPath) {
  // 20 000 triangles: sampled top ranges (8 192 or more), two sets of bins,
  // 32, 16 and 8 bins; the mixed scene: degenerate, duplicate and
  // non-finite triangles, median cuts of inseparable ranges.
  TestMesh mixed = accel_test::mixedScene(5);
  std::mt19937 random(5);
  accel_test::addDegenerateAndDuplicates(mixed, 50, random);
  accel_test::poisonSomeTriangles(mixed);
  for (const TestMesh& mesh : {accel_test::furnishedHall(20000, 5), mixed})
    for (const bool avx : {true, false}) {
      expectEveryTriangleOnce(mesh, buildWith<8>(mesh, avx));
      expectEveryTriangleOnce(mesh, buildWith<4>(mesh, avx));
    }
}

// The triangles of a leaf (its packets' distinct ids).
template <int Width>
std::vector<uint32_t> leafPrimitives(const BvhData<Width>& tree, uint32_t child) {
  std::vector<uint32_t> primitives;
  for (uint32_t p = 0; p < bvh_child::packetCount(child); ++p)
    for (const uint32_t primitive : tree.packets[bvh_child::firstPacket(child) + p].primitive)
      if (std::find(primitives.begin(), primitives.end(), primitive) == primitives.end()) primitives.push_back(primitive);
  return primitives;
}

double halfArea(const Bounds3& box) {
  const Vec3 d = box.diagonal();
  return double(d.x) * d.y + double(d.y) * d.z + double(d.z) * d.x;
}

TEST(BvhBuild, PutsTheRoomsLargeTrianglesInLeavesOfTheRoot) {
  // A hall's shell: floor, ceiling and four walls, two triangles each, each
  // of at least 1/64 of the root's half area; the furniture's are far smaller.
  const TestMesh hall = accel_test::furnishedHall(20000, 6);
  const BvhData<8> tree = buildBvh<8>(hall.view());
  const double rootArea = halfArea(tree.bounds);
  std::vector<uint32_t> large;
  for (uint32_t t = 0; t < hall.triangleCount(); ++t) {
    Bounds3 box;
    for (int vertex = 0; vertex < 3; ++vertex) box.extend(hall.vertex(hall.indices[3 * t + vertex]));
    if (halfArea(box) * 64 >= rootArea) large.push_back(t);
  }
  ASSERT_EQ(large.size(), 12u);
  std::vector<uint32_t> inRootLeaves;
  int rootLeaves = 0;
  for (int k = 0; k < 8; ++k) {
    const uint32_t child = tree.nodes[0].child[k];
    if (!(tree.nodes[0].box[0][0][k] <= tree.nodes[0].box[0][1][k]) || !bvh_child::isLeaf(child)) continue;
    ++rootLeaves;
    const std::vector<uint32_t> primitives = leafPrimitives(tree, child);
    EXPECT_EQ(primitives.size(), 2u);   // one rectangle
    inRootLeaves.insert(inRootLeaves.end(), primitives.begin(), primitives.end());
    // Flat: the rectangle's plane.
    int flatAxes = 0;
    for (int axis = 0; axis < 3; ++axis) flatAxes += tree.nodes[0].box[axis][0][k] == tree.nodes[0].box[axis][1][k];
    EXPECT_EQ(flatAxes, 1);
  }
  EXPECT_EQ(rootLeaves, 6);
  std::sort(inRootLeaves.begin(), inRootLeaves.end());
  EXPECT_EQ(inRootLeaves, large);
  expectEveryTriangleOnce(hall, tree);
}

TEST(BvhBuild, KeepsLargeTrianglesInTheTreeWhenTheyWouldTakeTooManyOfTheRootsSlots) {
  // The hall's six rectangles in a 4-wide tree, whose root has room for
  // two such leaves: none is made; the root's children are the SAH's, each
  // over thousands of triangles.
  const TestMesh hall = accel_test::furnishedHall(20000, 6);
  const BvhData<4> tree = buildBvh<4>(hall.view());
  for (int k = 0; k < 4; ++k) EXPECT_FALSE(bvh_child::isLeaf(tree.nodes[0].child[k])) << k;
  expectEveryTriangleOnce(hall, tree);
}

TEST(BvhBuild, BuildsTheSameTreeBitForBitEveryTime) {
  const TestMesh hall = accel_test::furnishedHall(20000, 9);
  expectSameTree(buildBvh<8>(hall.view()), buildBvh<8>(hall.view()));
  expectSameTree(buildBvh<4>(hall.view()), buildBvh<4>(hall.view()));
}

TEST(BvhSahCost, CountsTheRootTestAndEachChildByItsShareOfTheRootsArea) {
  // Four triangles: one leaf of one packet under the root, both of the
  // root's box: one node test and one packet test.
  TestMesh four;
  for (int i = 0; i < 4; ++i) four.addTriangle({0, 0, float(i)}, {1, 0, float(i)}, {0, 1, float(i) + 0.5f});
  EXPECT_EQ(bvhSahCost(buildBvh<8>(four.view())), 2.0);
  EXPECT_EQ(bvhSahCost(buildBvh<4>(four.view())), 2.0);
  EXPECT_EQ(bvhSahCost(buildBvh<8>(TestMesh().view())), 0.0);
  // A hall: more than the root's test, less than testing every packet
  // from the root; a 4-wide tree tests more nodes than an 8-wide one.
  const TestMesh hall = accel_test::furnishedHall(20000, 4);
  const BvhData<8> eight = buildBvh<8>(hall.view());
  const BvhData<4> fourWide = buildBvh<4>(hall.view());
  EXPECT_GT(bvhSahCost(eight), 2.0);
  EXPECT_LT(bvhSahCost(eight), 1.0 + double(eight.packets.size()) / 4);
  EXPECT_GT(bvhSahCost(fourWide), bvhSahCost(eight));
}

TEST(BvhBuild, AvxBinningCanBeTurnedOffAndOn) {
  useBvhAvxBinning(false);
  EXPECT_FALSE(bvhAvxBinningInUse());
  useBvhAvxBinning(true);
  EXPECT_EQ(bvhAvxBinningInUse(), __builtin_cpu_supports("avx") != 0);
}

}  // namespace
}  // namespace portico
