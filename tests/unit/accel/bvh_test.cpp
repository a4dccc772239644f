#include "common/accel/bvh.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/accel/accelerator.h"
#include "common/accel/brute_force.h"
#include "common/accel/bvh_traverse_avx2.h"
#include "common/accel/triangle_intersect.h"
#include "common/triangle_box_overlap.h"
#include "tests/unit/accel/accel_test_scenes.h"

namespace portico {
namespace {

using accel_test::errorOf;

using accel_test::describe;
using accel_test::sameBits;
using accel_test::TestMesh;

const char* const kBvhSpecs[] = {"bvh:width=4", "bvh:width=8"};
constexpr int kGrazingRays = 6000;

std::unique_ptr<Accelerator> buildBvh(const TestMesh& mesh, const std::string& spec) {
  return buildAccelerator(parseAcceleratorSpec(spec), mesh.view());
}

// The faces of the tree's boxes along one axis, to start rays on them.
std::vector<float> boxFaces(const Accelerator& bvh, int axis) {
  std::vector<float> faces;
  const auto collect = [&](const auto& data) {
    for (const auto& node : data.nodes)
      for (int side = 0; side < 2; ++side)
        for (float face : node.box[axis][side])
          if (std::isfinite(face)) faces.push_back(face);
  };
  if (const auto* four = dynamic_cast<const WideBvh<4>*>(&bvh)) collect(four->data());
  if (const auto* eight = dynamic_cast<const WideBvh<8>*>(&bvh)) collect(eight->data());
  return faces;
}

// The shared rays (some starting on box faces), plus rays through points of
// edges, and rays from vertices along the axes (grazing the faces they touch).
std::vector<Ray> testRays(const TestMesh& mesh, const Accelerator& bvh, int count, uint32_t seed) {
  std::vector<float> faces[3];
  for (int axis = 0; axis < 3; ++axis) faces[axis] = boxFaces(bvh, axis);
  std::vector<Ray> rays = accel_test::testRays(mesh, count, seed, [&](int axis, std::mt19937& random) {
    return faces[axis].empty() ? 0.0f : faces[axis][random() % faces[axis].size()];
  });
  std::mt19937 random(seed + 1);
  std::uniform_real_distribution<float> unit(0, 1);
  const Bounds3 box = mesh.bounds();
  for (int i = 0; i < count / 4 && mesh.triangleCount() > 0; ++i) {
    const uint32_t* t = &mesh.indices[3 * (random() % mesh.triangleCount())];
    const Vec3 a = mesh.vertex(t[0]), c = mesh.vertex(t[2]);
    if (i % 2 == 0) {
      const Vec3 target = a + (c - a) * (random() % 2 ? 0.5f : unit(random));
      const Vec3 origin = box.lo + (box.hi - box.lo) * Vec3(unit(random), unit(random), unit(random));
      rays.push_back(Ray{origin, target - origin});
    } else {
      Vec3 d(0.0f);
      d[int(random() % 3)] = random() % 2 ? 1.0f : -1.0f;
      if (random() % 4 == 0) d[int(random() % 3)] = -0.0f;
      rays.push_back(Ray{a, d, random() % 2 ? 1e-4f : 0.0f});
    }
  }
  return rays;
}

// Each BVH must agree with brute force exactly: same primitive, same bits.
void expectSameAsBruteForce(const TestMesh& mesh, const std::vector<const Accelerator*>& bvhs,
                            const std::vector<Ray>& rays, double minimumHitFraction = 0.1) {
  const BruteForce brute(mesh.view());
  std::vector<int> mismatches(bvhs.size(), 0);
  int hits = 0;
  for (const Ray& ray : rays) {
    const Hit expected = brute.intersect(ray);
    hits += expected.found();
    for (size_t i = 0; i < bvhs.size(); ++i) {
      const Hit got = bvhs[i]->intersect(ray);
      const bool sameOcclusion = bvhs[i]->occluded(ray) == expected.found();
      if ((!sameBits(got, expected) || !sameOcclusion) && ++mismatches[i] <= 5)
        ADD_FAILURE() << bvhs[i]->stats().spec << ": " << describe(ray) << ": brute force primitive "
                      << expected.primitive << " t " << expected.t << ", bvh primitive " << got.primitive << " t "
                      << got.t << (sameOcclusion ? "" : " (occluded() disagrees)");
    }
  }
  for (size_t i = 0; i < bvhs.size(); ++i) EXPECT_EQ(mismatches[i], 0) << bvhs[i]->stats().spec;
  EXPECT_GT(hits, minimumHitFraction * double(rays.size()));
}

// Both widths, the 8-wide one with its AVX2 traversal (where the processor
// has it) and with SSE, on the shared rays starting on the 4-wide tree's box faces.
void expectSameAsBruteForce(const TestMesh& mesh, int rayCount, uint32_t seed, double minimumHitFraction = 0.1,
                            const TestMesh* rayMesh = nullptr) {
  const auto four = buildBvh(mesh, "bvh:width=4"), eight = buildBvh(mesh, "bvh:width=8");
  const std::vector<Ray> rays = testRays(rayMesh ? *rayMesh : mesh, *four, rayCount, seed);
  expectSameAsBruteForce(mesh, {four.get(), eight.get()}, rays, minimumHitFraction);
  useBvhAvx2(false);
  expectSameAsBruteForce(mesh, {eight.get()}, rays, minimumHitFraction);
  useBvhAvx2(true);
}

TestMesh mixedScene(uint32_t seed) {
  TestMesh mesh = accel_test::mixedScene(seed);
  std::mt19937 random(seed);
  accel_test::addDegenerateAndDuplicates(mesh, 30, random);
  return mesh;
}

TEST(Bvh, MatchesBruteForceOnRandomTriangles) {
  std::mt19937 random(1);
  TestMesh mesh;
  accel_test::addRandomTriangles(mesh, 2000, random);
  expectSameAsBruteForce(mesh, 8000, 100);
}

TEST(Bvh, MatchesBruteForceInAFurnishedRoom) {
  std::mt19937 random(2);
  TestMesh mesh;
  accel_test::addRoomOfBoxes(mesh, random, /*boxes=*/40, /*duplicates=*/40);
  expectSameAsBruteForce(mesh, 16000, 200);
}

TEST(Bvh, MatchesBruteForceInAFurnishedHall) {
  const TestMesh mesh = accel_test::furnishedHall(10000, 3);
  expectSameAsBruteForce(mesh, 5000, 300);
}

TEST(Bvh, MatchesBruteForceOnLongThinTrianglesAndAClusterInAnEmptyRoom) {
  std::mt19937 random(4);
  TestMesh thin, cluster;
  accel_test::addLongThinTriangles(thin, 500, random);
  accel_test::addClusterInEmptyRoom(cluster, 1500, random);
  expectSameAsBruteForce(thin, 8000, 400, 0.02);
  expectSameAsBruteForce(cluster, 8000, 401, 0.5);
}

TEST(Bvh, MatchesBruteForceWithDegenerateAndDuplicateTriangles) {
  std::mt19937 random(5);
  TestMesh mesh;
  accel_test::addRoomOfBoxes(mesh, random);
  accel_test::addRandomTriangles(mesh, 200, random);
  accel_test::addDegenerateAndDuplicates(mesh, 200, random);
  expectSameAsBruteForce(mesh, 10000, 500);
  // Hundreds of copies of one triangle: leaves cut from a range of equal centroids.
  TestMesh copies;
  for (int i = 0; i < 300; ++i) copies.addTriangle({0, 0, 0}, {1, 0, 0}, {0, 1, 0});
  accel_test::addRandomTriangles(copies, 50, random);
  expectSameAsBruteForce(copies, 3000, 501, 0.02);
}

TEST(Bvh, MatchesBruteForceFarFromTheWorldOrigin) {
  std::mt19937 random(6);
  TestMesh mesh;
  accel_test::addRoomOfBoxes(mesh, random);
  accel_test::addRandomTriangles(mesh, 300, random);
  accel_test::moveFarFromTheOrigin(mesh);
  expectSameAsBruteForce(mesh, 10000, 600);
}

// Nearly edge-on hits, where the watertight test rounds most: in a
// furnished hall at building coordinates, among long thin triangles, and
// far from the world's origin; both widths, AVX2 and SSE.
// A voxel cell (scene import --grid): every triangle of a furnished hall
// that touches one voxel, whole, so the cell's triangles reach past the
// voxel; rays start inside the voxel and on its faces, as a cell's rays do.
TEST(Bvh, MatchesBruteForceInAVoxelCell) {
  const TestMesh hall = accel_test::furnishedHall(30000, 17);
  const Bounds3 bounds = hall.bounds();
  const Vec3 size = bounds.diagonal() * (1.0f / 3.0f);
  for (const Vec3& corner : {Vec3(0, 0, 0), Vec3(1, 0, 1), Vec3(2, 0, 1)}) {
    const Bounds3 voxel{bounds.lo + size * corner, bounds.lo + size * (corner + Vec3(1, 3, 1))};
    TestMesh cell;
    for (size_t t = 0; t < hall.triangleCount(); ++t) {
      const Vec3 a = hall.vertex(hall.indices[3 * t]), b = hall.vertex(hall.indices[3 * t + 1]),
                 c = hall.vertex(hall.indices[3 * t + 2]);
      if (triangleOverlapsBox(a, b, c, voxel, 1e-4f)) cell.addTriangle(a, b, c);
    }
    ASSERT_GT(cell.triangleCount(), 100u);
    // Rays from inside the voxel, some from its faces.
    std::mt19937 random(uint32_t(corner.x * 7 + corner.z));
    std::uniform_real_distribution<float> unit(0, 1), symmetric(-1, 1);
    std::vector<Ray> rays;
    for (int i = 0; i < 2500; ++i) {
      Vec3 origin = voxel.lo + (voxel.hi - voxel.lo) * Vec3(unit(random), unit(random), unit(random));
      if (i % 3 == 0) {
        const int axis = int(random() % 3);
        origin[axis] = random() % 2 ? voxel.lo[axis] : voxel.hi[axis];
      }
      Vec3 direction;
      do direction = {symmetric(random), symmetric(random), symmetric(random)};
      while (dot(direction, direction) < 1e-4f);
      rays.push_back(Ray{origin, direction});
    }
    const auto four = buildBvh(cell, "bvh:width=4"), eight = buildBvh(cell, "bvh:width=8");
    expectSameAsBruteForce(cell, {four.get(), eight.get()}, rays, 0.3);
    useBvhAvx2(false);
    expectSameAsBruteForce(cell, {eight.get()}, rays, 0.3);
    useBvhAvx2(true);
  }
}

TEST(Bvh, MatchesBruteForceOnGrazingRays) {
  std::mt19937 random(11);
  TestMesh thin;
  accel_test::addLongThinTriangles(thin, 200, random);
  accel_test::addRoomOfBoxes(thin, random);
  TestMesh far = mixedScene(12);
  accel_test::moveFarFromTheOrigin(far);
  const TestMesh hall = accel_test::furnishedHall(10000, 13);
  uint32_t seed = 1100;
  for (const TestMesh* mesh : std::initializer_list<const TestMesh*>{&hall, &thin, &far}) {
    const auto four = buildBvh(*mesh, "bvh:width=4"), eight = buildBvh(*mesh, "bvh:width=8");
    const std::vector<Ray> rays = accel_test::grazingRays(*mesh, kGrazingRays, ++seed);
    expectSameAsBruteForce(*mesh, {four.get(), eight.get()}, rays, 0.3);
    useBvhAvx2(false);
    expectSameAsBruteForce(*mesh, {eight.get()}, rays, 0.3);
    useBvhAvx2(true);
  }
}

TEST(Bvh, MatchesBruteForceWithNonFiniteTriangles) {
  const TestMesh intact = mixedScene(7);
  TestMesh mesh = intact;
  accel_test::poisonSomeTriangles(mesh);
  expectSameAsBruteForce(mesh, 5000, 700, 0.1, &intact);
}

TEST(Bvh, HandlesFlatBoundsAndBreaksTiesBySmallerId) {
  // A floor: every vertex at z = 1, so every box is flat.
  TestMesh floor;
  accel_test::addFloor(floor);
  const BruteForce brute(floor.view());
  for (const char* spec : kBvhSpecs) {
    SCOPED_TRACE(spec);
    const auto bvh = buildBvh(floor, spec);
    EXPECT_GT(bvh->stats().nodes, 1u);
    expectSameAsBruteForce(floor, {bvh.get()}, testRays(floor, *bvh, 6000, 800), 0.02);
    // Straight down onto shared vertices and edges: ties broken by the smaller id.
    for (const Vec3 origin : {Vec3(5, 5, 3), Vec3(7, 3, 3), Vec3(0, 0, 3), Vec3(10, 20, 3), Vec3(4.5f, 6, 3)}) {
      const Ray ray{origin, {0, 0, -1}};
      const Hit hit = bvh->intersect(ray);
      ASSERT_TRUE(hit.found());
      EXPECT_EQ(hit.t, 2.0f);
      EXPECT_EQ(hit.primitive, brute.intersect(ray).primitive);
    }
  }
}

TEST(Bvh, MatchesBruteForceForTinyAndHugeDirections) {
  const TestMesh mesh = mixedScene(9);
  std::mt19937 random(90);
  std::uniform_real_distribution<float> coordinate(-2, 12), symmetric(-1, 1);
  std::vector<Ray> rays;
  for (int i = 0; i < 3000; ++i) {
    Vec3 d{symmetric(random), symmetric(random), symmetric(random)};
    const float scales[] = {1e-39f, 1e-30f, 1e-20f, 1e20f, 1e30f, 1e38f};
    d[int(random() % 3)] *= scales[random() % 6];
    if (i % 5 == 0) d = d * 1e-38f;  // every component tiny
    rays.push_back(Ray{{coordinate(random), coordinate(random), coordinate(random)}, d});
  }
  const auto four = buildBvh(mesh, "bvh:width=4"), eight = buildBvh(mesh, "bvh:width=8");
  expectSameAsBruteForce(mesh, {four.get(), eight.get()}, rays, 0.05);
}

TEST(Bvh, HandlesEmptyAndDegenerateMeshesAndBadRays) {
  const TestMesh empty;
  TestMesh degenerate;
  degenerate.addTriangle({2, 2, 2}, {2, 2, 2}, {2, 2, 2});
  degenerate.addTriangle({0, 0, 0}, {1, 1, 1}, {2, 2, 2});
  TestMesh one;
  one.addTriangle({0, 0, 0}, {1, 0, 0}, {0, 1, 0});
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (const char* spec : kBvhSpecs) {
    SCOPED_TRACE(spec);
    for (const TestMesh* mesh : {&empty, static_cast<const TestMesh*>(&degenerate)}) {
      const auto bvh = buildBvh(*mesh, spec);
      EXPECT_FALSE(bvh->intersect(Ray{{0, 0, 0}, {1, 1, 1}}).found());
      EXPECT_FALSE(bvh->occluded(Ray{{0, 0, 0}, {1, 1, 1}}));
      EXPECT_TRUE(bvh->bounds().empty());
      EXPECT_EQ(bvh->stats().nodes, 0u);
      EXPECT_EQ(bvh->stats().leaves, 0u);
      EXPECT_EQ(bvh->stats().triangleReferences, 0u);
    }
    const auto bvh = buildBvh(one, spec);
    EXPECT_EQ(bvh->stats().nodes, 1u);
    EXPECT_EQ(bvh->stats().leaves, 1u);
    EXPECT_EQ(bvh->intersect(Ray{{0.25f, 0.25f, 1}, {0, 0, -1}}).primitive, 0u);
    for (const Ray& ray : {Ray{{0.2f, 0.2f, 5}, {0, 0, 0}}, Ray{{nan, 0.2f, 5}, {0, 0, -1}},
                           Ray{{0.2f, 0.2f, 5}, {0, nan, -1}}, Ray{{0.2f, 0.2f, 5}, {0, 0, -1}, 6.0f, 1.0f},
                           Ray{{0.2f, 0.2f, 5}, {0, 0, -1}, nan, 10.0f}, Ray{{0.2f, 0.2f, kInfinity}, {0, 0, -1}},
                           Ray{{0.2f, 0.2f, 5}, {0, 0, -1}, 0.0f, 4.5f}}) {
      EXPECT_FALSE(bvh->intersect(ray).found()) << describe(ray);
      EXPECT_FALSE(bvh->occluded(ray)) << describe(ray);
    }
  }
}

TEST(Bvh, AnswersFromManyThreadsAtOnce) {
  const TestMesh mesh = mixedScene(10);
  for (const char* spec : kBvhSpecs) {
    const auto bvh = buildBvh(mesh, spec);
    const std::vector<Ray> rays = testRays(mesh, *bvh, 3000, 1000);
    for (int count : accel_test::mismatchesFromManyThreads(*bvh, rays, 3, sameBits)) EXPECT_EQ(count, 0) << spec;
  }
}

// Every held triangle in exactly one leaf, every box holding its subtree,
// at most 8 triangles a leaf (16 in 8-wide trees, whose leaves are tested two
// packets at a time), statistics that count what is there.
template <int Width>
void expectWellFormed(const TestMesh& mesh, const WideBvh<Width>& bvh) {
  const BvhData<Width>& data = bvh.data();
  std::vector<int> seen(mesh.triangleCount(), 0);
  uint64_t leaves = 0, held = 0;
  uint32_t deepest = 0;
  const std::function<void(uint32_t, const Bounds3&, uint32_t)> visit = [&](uint32_t child, const Bounds3& box,
                                                                            uint32_t depth) {
    deepest = std::max(deepest, depth);
    if (bvh_child::isLeaf(child)) {
      ++leaves;
      std::vector<uint32_t> primitives;
      for (uint32_t p = 0; p < bvh_child::packetCount(child); ++p) {
        const auto& packet = data.packets[bvh_child::firstPacket(child) + p];
        for (int lane = 0; lane < 4; ++lane) {
          const uint32_t primitive = packet.primitive[lane];
          if (std::find(primitives.begin(), primitives.end(), primitive) != primitives.end()) continue;
          primitives.push_back(primitive);
          ++seen[primitive];
          const uint32_t* t = &mesh.indices[3 * primitive];
          for (int vertex = 0; vertex < 3; ++vertex) {
            const Vec3 v = mesh.vertex(t[vertex]);
            EXPECT_TRUE(box.contains(v));
            for (int axis = 0; axis < 3; ++axis) EXPECT_EQ(packet.v[vertex][axis][lane], v[axis]);
          }
        }
      }
      EXPECT_LE(primitives.size(), Width == 8 ? 16u : 8u);
      held += primitives.size();
      return;
    }
    const BvhNode<Width>& node = data.nodes[child];
    for (int k = 0; k < Width; ++k) {
      const Bounds3 childBox({node.box[0][0][k], node.box[1][0][k], node.box[2][0][k]},
                             {node.box[0][1][k], node.box[1][1][k], node.box[2][1][k]});
      if (childBox.empty()) continue;   // an unused slot
      EXPECT_TRUE(box.contains(childBox.lo) && box.contains(childBox.hi));
      visit(node.child[k], childBox, depth + 1);
    }
  };
  ASSERT_FALSE(data.nodes.empty());
  visit(0, bvh.bounds(), 1);
  for (size_t t = 0; t < mesh.triangleCount(); ++t) {
    const uint32_t* v = &mesh.indices[3 * t];
    const bool degenerate = isDegenerateTriangle(mesh.vertex(v[0]), mesh.vertex(v[1]), mesh.vertex(v[2]));
    EXPECT_EQ(seen[t], degenerate ? 0 : 1) << t;
  }
  const AcceleratorStats& stats = bvh.stats();
  EXPECT_EQ(stats.leaves, leaves);
  EXPECT_EQ(stats.triangleReferences, held);
  EXPECT_EQ(stats.maxDepth, deepest);
  EXPECT_LE(stats.maxDepth, uint32_t(kBvhMaxDepth));
  EXPECT_GE(stats.averageDepth, 2.0);
  EXPECT_EQ(stats.nodes, data.nodes.size());
  EXPECT_GE(stats.bytes, stats.nodes * sizeof(BvhNode<Width>));
  EXPECT_GE(stats.buildMs, 0.0);
}

TEST(Bvh, IsWellFormedAndReportsConsistentStatistics) {
  const TestMesh mixed = mixedScene(11);
  const TestMesh hall = accel_test::furnishedHall(5000, 11);
  for (const TestMesh* mesh : {&mixed, &hall}) {
    expectWellFormed(*mesh, WideBvh<4>(mesh->view(), "bvh:width=4"));
    expectWellFormed(*mesh, WideBvh<8>(mesh->view(), "bvh:width=8"));
  }
  // A wider tree is shallower.
  const WideBvh<4> four(hall.view(), "bvh:width=4");
  const WideBvh<8> eight(hall.view(), "bvh:width=8");
  EXPECT_LT(eight.stats().averageDepth, four.stats().averageDepth);
  EXPECT_LT(eight.stats().nodes, four.stats().nodes);
}

TEST(BvhSpec, BuildsEachWidthAndRejectsBadSpecs) {
  const TestMesh mesh = mixedScene(12);
  const auto plain = buildBvh(mesh, "bvh");
  EXPECT_EQ(plain->stats().spec, "bvh");
  EXPECT_NE(dynamic_cast<const WideBvh<8>*>(plain.get()), nullptr);
  EXPECT_NE(dynamic_cast<const WideBvh<4>*>(buildBvh(mesh, "bvh:width=4").get()), nullptr);
  EXPECT_NE(dynamic_cast<const WideBvh<8>*>(buildBvh(mesh, "bvh:width=8").get()), nullptr);
  EXPECT_EQ(plain->bounds().lo, BruteForce(mesh.view()).bounds().lo);
  EXPECT_EQ(plain->bounds().hi, BruteForce(mesh.view()).bounds().hi);

  const auto buildError = [&](const char* text) { return errorOf([&] { buildBvh(mesh, text); }); };
  EXPECT_EQ(buildError("bvh:width=6"), "accelerator spec 'bvh:width=6': parameter width must be 4 or 8 (got 6)");
  EXPECT_EQ(buildError("bvh:width=16"), "accelerator spec 'bvh:width=16': parameter width must be 4 or 8 (got 16)");
  EXPECT_EQ(buildError("bvh:width=x"), "accelerator spec 'bvh:width=x': parameter width must be a positive integer (got 'x')");
  EXPECT_EQ(buildError("bvh:width=0"), "accelerator spec 'bvh:width=0': parameter width must be a positive integer (got '0')");
  EXPECT_EQ(buildError("bvh:leaf=4"), "accelerator spec 'bvh:leaf=4': unknown parameter 'leaf' for bvh (it takes: width)");
  EXPECT_EQ(buildError("bvh:sah"), "accelerator spec 'bvh:sah': bvh takes no variant (got 'sah')");
  EXPECT_THROW(validateAcceleratorSpec(parseAcceleratorSpec("bvh:width=5")), std::invalid_argument);
  EXPECT_NO_THROW(validateAcceleratorSpec(parseAcceleratorSpec("bvh:width=8")));
  const std::vector<std::string_view> kinds = acceleratorKinds();
  EXPECT_NE(std::find(kinds.begin(), kinds.end(), "bvh"), kinds.end());
}

}  // namespace
}  // namespace portico
