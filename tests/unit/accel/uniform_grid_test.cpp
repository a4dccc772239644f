#include "common/accel/uniform_grid.h"

#include <gtest/gtest.h>

#include <array>
#include <bit>
#include <functional>
#include <limits>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "common/accel/accelerator.h"
#include "common/accel/brute_force.h"
#include "tests/unit/accel/accel_test_scenes.h"

namespace portico {
namespace {

using accel_test::errorOf;

using accel_test::addRandomTriangles;
using accel_test::addLongThinTriangles;
using accel_test::describe;
using accel_test::mixedScene;
using accel_test::TestMesh;

// Rooms of a building: a shell, walls, stacked boxes sharing faces (coplanar
// overlapping triangles: ties), all on a 0.5 lattice so faces fall on voxel
// boundaries for many resolutions, plus exact duplicates of some triangles.
void addRoom(TestMesh& mesh, std::mt19937& random) { accel_test::addRoomOfBoxes(mesh, random); }

// Rays of every kind the grid must get right, some starting on voxel boundaries.
std::vector<Ray> testRays(const TestMesh& mesh, const UniformGrid& grid, int count, uint32_t seed) {
  const auto low = grid.gridLow();
  const auto size = grid.voxelSize();
  const auto resolution = grid.resolution();
  return accel_test::testRays(mesh, count, seed, [&](int axis, std::mt19937& random) {
    return float(low[axis] + size[axis] * double(random() % (resolution[axis] + 1)));
  });
}

// The grid must agree with brute force exactly: same primitive, same bits.
void expectSameAsBruteForce(const TestMesh& mesh, const UniformGrid& grid, int rayCount, uint32_t seed,
                            double minimumHitFraction = 0.1) {
  const BruteForce brute(mesh.view());
  int hits = 0, mismatches = 0;
  for (const Ray& ray : testRays(mesh, grid, rayCount, seed)) {
    const Hit expected = brute.intersect(ray);
    const Hit got = grid.intersect(ray);
    hits += expected.found();
    const bool same = accel_test::sameBits(got, expected);
    const bool sameOcclusion = grid.occluded(ray) == expected.found();
    if ((!same || !sameOcclusion) && ++mismatches <= 5)
      ADD_FAILURE() << describe(ray) << ": brute force primitive " << expected.primitive << " t "
                    << expected.t << ", grid primitive " << got.primitive << " t " << got.t
                    << (sameOcclusion ? "" : " (occluded() disagrees)");
  }
  EXPECT_EQ(mismatches, 0);
  EXPECT_GT(hits, minimumHitFraction * rayCount);  // the rays do hit things
}

TEST(UniformGrid, MatchesBruteForceWithAutomaticResolution) {
  const TestMesh mesh = mixedScene(1);
  const UniformGrid grid(mesh.view());
  expectSameAsBruteForce(mesh, grid, 20000, 100);
}

TEST(UniformGrid, MatchesBruteForceAtExplicitResolutions) {
  const TestMesh mesh = mixedScene(2);
  for (int resolution : {1, 2, 3, 7, 16, 20, 64, 200}) {
    SCOPED_TRACE("res=" + std::to_string(resolution));
    const UniformGrid grid(mesh.view(), UniformGridOptions{resolution});
    expectSameAsBruteForce(mesh, grid, 4000, 200 + resolution);
  }
}

TEST(UniformGrid, MatchesBruteForceOnEachSceneKind) {
  std::mt19937 random(3);
  TestMesh triangles, room, thin;
  addRandomTriangles(triangles, 2000, random);
  addRoom(room, random);
  addLongThinTriangles(thin, 300, random);
  for (const TestMesh* mesh : {&triangles, &room, &thin}) {
    const UniformGrid automatic(mesh->view());
    expectSameAsBruteForce(*mesh, automatic, 6000, 300);
    const UniformGrid fine(mesh->view(), UniformGridOptions{100});
    expectSameAsBruteForce(*mesh, fine, 6000, 301);
  }
}

TEST(UniformGrid, MatchesBruteForceFarFromTheWorldOrigin) {
  // A cell of a large building: coordinates in the thousands, size ~10.
  std::mt19937 random(4);
  TestMesh local;
  addRoom(local, random);
  addRandomTriangles(local, 300, random);
  TestMesh far = local;
  accel_test::moveFarFromTheOrigin(far);
  const UniformGrid grid(far.view());
  expectSameAsBruteForce(far, grid, 10000, 400);
}

TEST(UniformGrid, MatchesBruteForceWithNonFiniteTriangles) {
  // Triangles with a NaN or infinite vertex are left out (brute force never
  // hits them): the first, the last, a run, and every seventh. Rays come
  // from the intact mesh.
  const TestMesh intact = mixedScene(9);
  TestMesh mesh = intact;
  accel_test::poisonSomeTriangles(mesh);
  const UniformGrid grid(mesh.view());
  const BruteForce brute(mesh.view());
  int hits = 0, mismatches = 0;
  for (const Ray& ray : testRays(intact, grid, 6000, 700)) {
    const Hit expected = brute.intersect(ray);
    hits += expected.found();
    mismatches += !accel_test::sameBits(grid.intersect(ray), expected) || grid.occluded(ray) != expected.found();
  }
  EXPECT_EQ(mismatches, 0);
  EXPECT_GT(hits, 600);
}

TEST(UniformGrid, HandlesFlatBounds) {
  // A floor: every vertex at z = 1, so the bounds have no thickness.
  TestMesh floor;
  accel_test::addFloor(floor);
  const UniformGrid grid(floor.view());
  EXPECT_EQ(grid.resolution()[2], 1);
  EXPECT_GE(grid.resolution()[0], 8);  // a 2D grid of about density * 800 voxels
  // Rays starting inside the flat bounds lie in the floor's plane and miss.
  expectSameAsBruteForce(floor, grid, 8000, 500, 0.05);
  // Straight down onto a shared vertex: both bounds exclusive, ties by id.
  const Hit hit = grid.intersect(Ray{{5, 5, 3}, {0, 0, -1}});
  ASSERT_TRUE(hit.found());
  EXPECT_EQ(hit.t, 2.0f);
  EXPECT_EQ(hit.primitive, BruteForce(floor.view()).intersect(Ray{{5, 5, 3}, {0, 0, -1}}).primitive);

  // A line of triangles: flat on two axes.
  TestMesh line;
  for (int i = 0; i < 10; ++i) line.addTriangle({float(i), 0, 0}, {float(i + 1), 0, 0}, {float(i), 0, 0});
  const UniformGrid lineGrid(line.view());
  EXPECT_EQ(lineGrid.resolution()[1], 1);
  EXPECT_EQ(lineGrid.resolution()[2], 1);
  EXPECT_FALSE(lineGrid.intersect(Ray{{0.5f, 1, 0}, {0, -1, 0}}).found());
}

TEST(UniformGrid, HandlesAnEmptyMesh) {
  const TestMesh empty;
  const UniformGrid grid(empty.view());
  const Ray ray{{0, 0, 0}, {1, 0, 0}};
  EXPECT_FALSE(grid.intersect(ray).found());
  EXPECT_FALSE(grid.occluded(ray));
  EXPECT_TRUE(grid.bounds().empty());
  EXPECT_EQ(grid.stats().nodes, 0u);
  EXPECT_EQ(grid.stats().triangleReferences, 0u);

  // Only degenerate triangles, all at one point.
  TestMesh point;
  point.addTriangle({2, 2, 2}, {2, 2, 2}, {2, 2, 2});
  const UniformGrid pointGrid(point.view());
  EXPECT_FALSE(pointGrid.intersect(Ray{{0, 0, 0}, {1, 1, 1}}).found());
  EXPECT_FALSE(pointGrid.occluded(Ray{{0, 0, 0}, {1, 1, 1}}));
}

TEST(UniformGrid, IgnoresRaysWithoutDirectionOrWithNaN) {
  const TestMesh mesh = mixedScene(5);
  const UniformGrid grid(mesh.view());
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (const Ray& ray : {Ray{{5, 5, 5}, {0, 0, 0}}, Ray{{nan, 5, 5}, {1, 0, 0}},
                         Ray{{5, 5, 5}, {1, nan, 0}}, Ray{{5, 5, 5}, {1, 0, 0}, 2.0f, 1.0f}}) {
    EXPECT_FALSE(grid.intersect(ray).found());
    EXPECT_FALSE(grid.occluded(ray));
  }
}

TEST(UniformGrid, ExplicitResolutionFollowsTheLongestAxis) {
  TestMesh mesh;
  mesh.addBox({0, 0, 0}, {8, 4, 2});
  const UniformGrid grid(mesh.view(), UniformGridOptions{64});
  EXPECT_EQ(grid.resolution(), (std::array<int, 3>{64, 32, 16}));
  EXPECT_EQ(grid.stats().nodes, 64u * 32u * 16u);
  const UniformGrid coarse(mesh.view(), UniformGridOptions{2});
  EXPECT_EQ(coarse.resolution(), (std::array<int, 3>{2, 1, 1}));
}

TEST(UniformGrid, AutomaticResolutionFollowsTriangleCountAndShape) {
  // About density * n near-cubic voxels.
  EXPECT_EQ(automaticGridResolution({10, 10, 10}, 1000, 3.0), (std::array<int, 3>{14, 14, 14}));
  EXPECT_EQ(automaticGridResolution({20, 10, 5}, 8000, 1.0), (std::array<int, 3>{40, 20, 10}));
  // A flat floor gets one voxel of thickness and a 2D grid of ~3000 voxels.
  EXPECT_EQ(automaticGridResolution({10, 10, 1e-3}, 1000, 3.0), (std::array<int, 3>{55, 55, 1}));
  // A corridor: a row of voxels.
  EXPECT_EQ(automaticGridResolution({100, 1, 1}, 10, 3.0), (std::array<int, 3>{30, 1, 1}));
  // Clamped to 256 per axis, at least 1.
  EXPECT_EQ(automaticGridResolution({1, 1, 1}, 100000000, 3.0), (std::array<int, 3>{256, 256, 256}));
  EXPECT_EQ(automaticGridResolution({1, 1, 1}, 0, 3.0), (std::array<int, 3>{1, 1, 1}));

  // The default: about 0.125 voxels per triangle.
  const TestMesh mesh = mixedScene(6);
  const UniformGrid grid(mesh.view());
  const double voxels = double(grid.stats().nodes);
  const double triangles = double(mesh.indices.size() / 3);
  EXPECT_GT(voxels, 0.0625 * triangles);
  EXPECT_LT(voxels, 0.25 * triangles);
}

TEST(UniformGrid, ReportsStatistics) {
  const TestMesh mesh = mixedScene(7);
  const UniformGrid grid(mesh.view(), UniformGridOptions{32}, "grid:res=32");
  const AcceleratorStats& stats = grid.stats();
  const auto resolution = grid.resolution();
  EXPECT_EQ(stats.spec, "grid:res=32");
  EXPECT_EQ(stats.nodes, uint64_t(resolution[0]) * resolution[1] * resolution[2]);
  EXPECT_EQ(stats.leaves + stats.emptyLeaves, stats.nodes);
  EXPECT_GT(stats.leaves, 0u);
  EXPECT_GT(stats.emptyLeaves, 0u);
  EXPECT_GE(stats.triangleReferences, mesh.indices.size() / 3);
  EXPECT_EQ(stats.averageDepth, 1.0);
  EXPECT_EQ(stats.maxDepth, 1u);
  EXPECT_GE(stats.bytes, (stats.nodes + 1 + stats.triangleReferences) * sizeof(uint32_t));
  EXPECT_GE(stats.buildMs, 0.0);
}

TEST(UniformGrid, AnswersFromManyThreadsAtOnce) {
  const TestMesh mesh = mixedScene(8);
  const UniformGrid grid(mesh.view());
  const std::vector<Ray> rays = testRays(mesh, grid, 4000, 800);
  const auto same = [](const Hit& a, const Hit& b) { return a.primitive == b.primitive && a.t == b.t; };
  for (int count : accel_test::mismatchesFromManyThreads(grid, rays, 3, same)) EXPECT_EQ(count, 0);
}

TEST(BruteForce, FindsTheNearestHitAndBreaksTiesBySmallerId) {
  TestMesh mesh;
  mesh.addTriangle({0, 0, 2}, {4, 0, 2}, {0, 4, 2});  // 0: farther
  mesh.addTriangle({0, 0, 1}, {4, 0, 1}, {0, 4, 1});  // 1: nearest
  mesh.addTriangle({0, 0, 1}, {4, 0, 1}, {0, 4, 1});  // 2: same t as 1
  const BruteForce brute(mesh.view());
  const Hit hit = brute.intersect(Ray{{1, 1, 0}, {0, 0, 1}});
  EXPECT_EQ(hit.primitive, 1u);
  EXPECT_EQ(hit.t, 1.0f);
  EXPECT_TRUE(brute.occluded(Ray{{1, 1, 0}, {0, 0, 1}}));
  EXPECT_FALSE(brute.occluded(Ray{{1, 1, 0}, {0, 0, 1}, 0, 1.0f}));
  EXPECT_EQ(brute.intersect(Ray{{1, 1, 0}, {0, 0, 1}, 1.0f, kInfinity}).primitive, 0u);
  EXPECT_EQ(brute.stats().triangleReferences, 3u);
}

// ---------------------------------------------------------------------------
// Specs

TEST(AcceleratorSpec, ParsesKindVariantAndParameters) {
  const AcceleratorSpec grid = parseAcceleratorSpec("grid");
  EXPECT_EQ(grid.kind, "grid");
  EXPECT_EQ(grid.variant, "");
  EXPECT_TRUE(grid.parameters.empty());
  EXPECT_EQ(grid.text, "grid");

  const AcceleratorSpec withRes = parseAcceleratorSpec("grid:res=64");
  EXPECT_EQ(withRes.kind, "grid");
  ASSERT_EQ(withRes.parameters.size(), 1u);
  EXPECT_EQ(withRes.parameters[0], (std::pair<std::string, std::string>{"res", "64"}));

  const AcceleratorSpec kd = parseAcceleratorSpec("kd:sah,leaf=4,depth=20");
  EXPECT_EQ(kd.kind, "kd");
  EXPECT_EQ(kd.variant, "sah");
  ASSERT_EQ(kd.parameters.size(), 2u);
  EXPECT_EQ(kd.parameters[1].first, "depth");
  EXPECT_EQ(kd.parameters[1].second, "20");

  EXPECT_EQ(parseAcceleratorSpec("hgrid: res=16 , max=64").parameters[1].second, "64");
}

TEST(AcceleratorSpec, RejectsMalformedSpecsNamingThem) {
  const auto parseError = [](const char* text) { return errorOf([&] { parseAcceleratorSpec(text); }); };
  EXPECT_EQ(parseError(""), "accelerator spec '': no accelerator kind before ':' (e.g. 'grid:res=64')");
  EXPECT_NE(parseError(":res=4").find("no accelerator kind"), std::string::npos);
  EXPECT_EQ(parseError("grid:"), "accelerator spec 'grid:': empty item in the list after ':'");
  EXPECT_NE(parseError("grid:res=4,,").find("empty item"), std::string::npos);
  EXPECT_NE(parseError("kd:sah,median").find("two variants ('sah' and 'median')"), std::string::npos);
  EXPECT_NE(parseError("grid:=4").find("without a name"), std::string::npos);
  EXPECT_NE(parseError("grid:res=").find("parameter res has no value"), std::string::npos);
  EXPECT_NE(parseError("grid:res=4,res=8").find("parameter res is given twice"), std::string::npos);
}

TEST(AcceleratorSpec, BuildRejectsUnknownKindsParametersAndBadValues) {
  const TestMesh mesh = mixedScene(9);
  const auto buildError = [&](const char* text) {
    return errorOf([&] { buildAccelerator(parseAcceleratorSpec(text), mesh.view()); });
  };
  // Other kinds join the list as they are written: check only the start and ours.
  const std::string unknownKind = buildError("octree");
  EXPECT_EQ(unknownKind.rfind("accelerator spec 'octree': unknown accelerator kind 'octree' (known kinds: brute, grid", 0), 0u)
      << unknownKind;
  EXPECT_EQ(buildError("grid:res=abc"),
            "accelerator spec 'grid:res=abc': parameter res must be a positive integer (got 'abc')");
  EXPECT_NE(buildError("grid:res=0").find("must be a positive integer"), std::string::npos);
  EXPECT_NE(buildError("grid:res=-3").find("must be a positive integer"), std::string::npos);
  EXPECT_NE(buildError("grid:res=12.5").find("must be a positive integer"), std::string::npos);
  EXPECT_NE(buildError("grid:res=99999999999999").find("res must be"), std::string::npos);
  EXPECT_EQ(buildError("grid:res=4096"),
            "accelerator spec 'grid:res=4096': parameter res must be at most 512 (got 4096)");
  EXPECT_EQ(buildError("grid:resolution=64"),
            "accelerator spec 'grid:resolution=64': unknown parameter 'resolution' for grid "
            "(it takes: res, density)");
  EXPECT_NE(buildError("grid:density=-1").find("density must be a positive number"), std::string::npos);
  EXPECT_NE(buildError("grid:density=nan").find("density must be a positive number"), std::string::npos);
  EXPECT_EQ(buildError("grid:sah"), "accelerator spec 'grid:sah': grid takes no variant (got 'sah')");
  EXPECT_EQ(buildError("brute:res=4"),
            "accelerator spec 'brute:res=4': unknown parameter 'res' for brute (it takes none)");

  // validateAcceleratorSpec finds the same problems without building.
  EXPECT_THROW(validateAcceleratorSpec(parseAcceleratorSpec("grid:res=abc")), std::invalid_argument);
  EXPECT_THROW(validateAcceleratorSpec(parseAcceleratorSpec("octree:sah")), std::invalid_argument);
  EXPECT_THROW(validateAcceleratorSpec(parseAcceleratorSpec("grid:sah")), std::invalid_argument);
  EXPECT_NO_THROW(validateAcceleratorSpec(parseAcceleratorSpec("grid:res=64,density=2")));
}

TEST(AcceleratorSpec, BuildsEachKnownKind) {
  const TestMesh mesh = mixedScene(10);
  const std::vector<std::string_view> kinds = acceleratorKinds();
  ASSERT_GE(kinds.size(), 2u);
  EXPECT_EQ(kinds[0], "brute");
  EXPECT_EQ(kinds[1], "grid");
  const auto brute = buildAccelerator(parseAcceleratorSpec("brute"), mesh.view());
  const auto automatic = buildAccelerator(parseAcceleratorSpec("grid"), mesh.view());
  const auto explicitRes = buildAccelerator(parseAcceleratorSpec("grid:res=24"), mesh.view());
  const auto sparse = buildAccelerator(parseAcceleratorSpec("grid:density=0.1"), mesh.view());
  const auto dense = buildAccelerator(parseAcceleratorSpec("grid:density=3"), mesh.view());
  EXPECT_EQ(explicitRes->stats().spec, "grid:res=24");
  EXPECT_LT(sparse->stats().nodes, automatic->stats().nodes);
  EXPECT_GT(dense->stats().nodes, automatic->stats().nodes);
  EXPECT_EQ(static_cast<const UniformGrid&>(*explicitRes).resolution()[0], 24);
  std::mt19937 random(11);
  std::uniform_real_distribution<float> coordinate(-2, 12);
  for (int i = 0; i < 2000; ++i) {
    const Ray ray{{coordinate(random), coordinate(random), coordinate(random)},
                  {coordinate(random) - 5, coordinate(random) - 5, coordinate(random) - 5}};
    const Hit expected = brute->intersect(ray);
    for (const auto* accelerator : {automatic.get(), explicitRes.get(), sparse.get(), dense.get()}) {
      const Hit hit = accelerator->intersect(ray);
      ASSERT_EQ(hit.primitive, expected.primitive);
      ASSERT_EQ(std::bit_cast<uint32_t>(hit.t), std::bit_cast<uint32_t>(expected.t));
      ASSERT_EQ(accelerator->occluded(ray), expected.found());
    }
  }
  EXPECT_EQ(brute->bounds().lo, automatic->bounds().lo);
  EXPECT_EQ(brute->bounds().hi, automatic->bounds().hi);
}

}  // namespace
}  // namespace portico
