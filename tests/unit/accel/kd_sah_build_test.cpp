// The kd:sah builder (kd_sah.cpp) on its own: the exactness invariant the
// traversal rests on, checked directly on the built trees (not through
// rays), over option variants that take the builder's other paths (few and
// many bins, no empty-space bonus, leaf and depth limits); and fingerprints
// of the trees, printed, so that a change to the builder meant to keep the
// trees (a faster build) can be shown to keep them: run this test before
// and after, and compare the lines "kd:sah fingerprint ...".
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "common/accel/kd_build.h"
#include "common/accel/kd_tree.h"
#include "tests/unit/accel/accel_test_scenes.h"

namespace portico {
namespace {

using accel_test::TestMesh;

// FNV-1a over the node array, the leaves' triangles and the statistics.
struct Fingerprint {
  uint64_t hash = 1469598103934665603ull;
  void add(uint64_t value) {
    for (int byte = 0; byte < 8; ++byte) {
      hash ^= (value >> (8 * byte)) & 255;
      hash *= 1099511628211ull;
    }
  }
};

uint64_t fingerprint(const KdTreeData& tree) {
  Fingerprint f;
  for (const KdNode& node : tree.nodes) f.add(uint64_t(node.payload) << 32 | node.bits);
  for (uint32_t primitive : tree.primitives) f.add(primitive);
  f.add(tree.leaves);
  f.add(tree.emptyLeaves);
  f.add(tree.triangleReferences);
  f.add(std::bit_cast<uint64_t>(tree.depthSum));
  f.add(tree.maxDepth);
  return f.hash;
}

// Whether leaf `node` lists the triangle.
bool leafHolds(const KdTreeData& tree, const KdNode& node, uint32_t primitive) {
  const uint32_t count = node.triangleCount();
  if (count == 1) return node.payload == primitive;
  for (uint32_t i = 0; i < count; ++i)
    if (tree.primitives[node.payload + i] == primitive) return true;
  return false;
}

// Whether the point lies, within `slack` on each axis, in the closed box of
// some leaf holding the triangle: every leaf whose box holds the point is
// reached (both children when the point is on, or within slack of, a plane).
bool inLeafHolding(const KdTreeData& tree, uint32_t node, const Vec3& p, float slack, uint32_t primitive) {
  const KdNode& n = tree.nodes[node];
  if (n.isLeaf()) return leafHolds(tree, n, primitive);
  const int axis = n.axis();
  const float split = n.split();
  if (p[axis] <= split + slack && inLeafHolding(tree, n.firstChild(), p, slack, primitive)) return true;
  return p[axis] >= split - slack && inLeafHolding(tree, n.firstChild() + 1, p, slack, primitive);
}

// The invariant of kd_build.h: every point of every triangle in the tree
// lies in the closed box of some leaf referencing it. Checked exactly at the
// vertices, and on a barycentric lattice of points (edges and inside)
// within a slack of float rounding (the lattice points are rounded).
void expectInvariant(const TestMesh& mesh, const KdTreeData& tree, const std::string& name) {
  if (tree.nodes.empty()) return;
  const Vec3 extent = tree.bounds.diagonal();
  const float slack = 4e-7f * std::max({extent.x, extent.y, extent.z, 1.0f});
  std::vector<bool> inTree(mesh.triangleCount(), false);
  for (const KdNode& node : tree.nodes) {
    if (!node.isLeaf()) continue;
    const uint32_t count = node.triangleCount();
    if (count == 1) inTree[node.payload] = true;
    for (uint32_t i = 0; count > 1 && i < count; ++i) inTree[tree.primitives[node.payload + i]] = true;
  }
  int failures = 0;
  constexpr int kSteps = 6;
  for (uint32_t t = 0; t < mesh.triangleCount() && failures < 5; ++t) {
    if (!inTree[t]) continue;
    const Vec3 v[3] = {mesh.vertex(mesh.indices[3 * t]), mesh.vertex(mesh.indices[3 * t + 1]),
                       mesh.vertex(mesh.indices[3 * t + 2])};
    for (const Vec3& corner : v)
      if (!inLeafHolding(tree, 0, corner, 0.0f, t)) {
        ADD_FAILURE() << name << ": vertex of triangle " << t << " in no leaf holding it";
        ++failures;
      }
    for (int i = 0; i <= kSteps; ++i)
      for (int j = 0; i + j <= kSteps; ++j) {
        const Vec3 p = v[0] + (v[1] - v[0]) * (float(i) / kSteps) + (v[2] - v[0]) * (float(j) / kSteps);
        if (!inLeafHolding(tree, 0, p, slack, t)) {
          ADD_FAILURE() << name << ": point (" << i << ", " << j << ") of triangle " << t
                        << " in no leaf holding it";
          ++failures;
        }
      }
  }
}

struct Variant {
  const char* name;
  KdTreeOptions options;
};

std::vector<Variant> variants() {
  std::vector<Variant> list;
  list.push_back({"default", {}});
  KdTreeOptions options;
  options.bins = 4;
  list.push_back({"bins=4", options});
  options.bins = 256;
  list.push_back({"bins=256", options});
  options = {};
  options.emptyBonus = 1.0;
  list.push_back({"empty=1", options});
  options = {};
  options.leafSize = 3;
  options.maxDepth = 12;
  list.push_back({"leaf=3,depth=12", options});
  options = {};
  options.traversalCost = 0.3;
  list.push_back({"traversal=0.3", options});
  return list;
}

TestMesh soupScene(uint32_t seed) {
  std::mt19937 random(seed);
  TestMesh mesh;
  accel_test::addRandomTriangles(mesh, 3000, random);
  accel_test::addRoomOfBoxes(mesh, random, 60, 40);
  accel_test::addLongThinTriangles(mesh, 200, random);
  accel_test::addClusterInEmptyRoom(mesh, 2000, random);
  return mesh;
}

void check(const TestMesh& mesh, const std::string& scene, bool invariant) {
  for (const Variant& variant : variants()) {
    KdTreeOptions options = variant.options;
    options.strategy = KdSplitStrategy::SurfaceArea;
    KdTreeData data;  // as built, before the traversal's layout (kd_tree.cpp)
    buildKdTreeSah(mesh.view(), options, data);
    std::printf("kd:sah fingerprint %s %s: %016llx nodes %zu leaves %llu refs %llu depth %u\n", scene.c_str(),
                variant.name, (unsigned long long)fingerprint(data), data.nodes.size(),
                (unsigned long long)data.leaves, (unsigned long long)data.triangleReferences, data.maxDepth);
    if (invariant) expectInvariant(mesh, data, scene + " " + variant.name);
  }
}

TEST(KdSahBuild, SoupsKeepTheInvariant) {
  for (uint32_t seed : {1u, 2u}) check(soupScene(seed), "soup" + std::to_string(seed), true);
}

TEST(KdSahBuild, FurnishedHallsKeepTheInvariant) {
  check(accel_test::furnishedHall(10000, 5), "hall10k", true);
  check(accel_test::furnishedHall(60000, 6), "hall60k", true);
}

// The benchmark's cells (bench accel's seed, 1), fingerprinted and built twice: 10 K
// and 100 K, or the sizes in PORTICO_KD_FINGERPRINT_SIZES (a comma-separated
// list; with callgrind's --toggle-collect=portico::buildKdTreeSah*, the
// build's instructions at one size).
TEST(KdSahBuild, BenchmarkHallFingerprints) {
  std::vector<size_t> sizes = {10000, 100000};
  if (const char* list = std::getenv("PORTICO_KD_FINGERPRINT_SIZES")) {
    sizes.clear();
    for (const char* p = list; *p;) {
      char* end = nullptr;
      sizes.push_back(size_t(std::strtoull(p, &end, 10)));
      if (end == p) break;
      p = *end == ',' ? end + 1 : end;
    }
  }
  for (size_t size : sizes) {
    const TestMesh mesh = accel_test::furnishedHall(size, 1);
    KdTreeData data;
    buildKdTreeSah(mesh.view(), KdTreeOptions{}, data);
    std::printf("kd:sah fingerprint bench%zu: %016llx nodes %zu leaves %llu refs %llu depth %u\n", size,
                (unsigned long long)fingerprint(data), data.nodes.size(), (unsigned long long)data.leaves,
                (unsigned long long)data.triangleReferences, data.maxDepth);
    EXPECT_GT(data.leaves, 0u);
    // The build is deterministic: the same cell gives the same tree, bit for
    // bit (what a builder change compares against its predecessor).
    KdTreeData again;
    buildKdTreeSah(mesh.view(), KdTreeOptions{}, again);
    EXPECT_EQ(fingerprint(again), fingerprint(data)) << size;
  }
}

}  // namespace
}  // namespace portico
