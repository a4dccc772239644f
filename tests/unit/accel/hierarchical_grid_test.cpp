#include "common/accel/hierarchical_grid.h"

#include <gtest/gtest.h>

#include <cstring>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "common/accel/accelerator.h"
#include "common/accel/brute_force.h"
#include "common/accel/uniform_grid.h"
#include "tests/unit/accel/accel_test_scenes.h"

namespace portico {
namespace {

using accel_test::TestMesh;

// Rays with coordinates on the voxel boundaries of every grid of the hierarchy.
std::vector<Ray> hierarchyRays(const TestMesh& mesh, const HierarchicalGrid& grid, int count, uint32_t seed) {
  const auto& grids = grid.grids();
  return accel_test::testRays(mesh, count, seed, [&](int axis, std::mt19937& random) {
    if (grids.empty()) return 0.0f;
    const HierarchicalGrid::GridRecord& record = grids[random() % grids.size()];
    const int boundary = int(random() % uint32_t(record.resolution[axis] + 1));
    return float(record.low[axis] + record.voxelSize[axis] * boundary);
  });
}

// The hierarchical grid must agree with brute force exactly: same primitive,
// same bits of t, u and v, and the same answer to occluded().
void expectSameAsBruteForce(const TestMesh& mesh, const HierarchicalGrid& grid, int rayCount, uint32_t seed,
                            double minimumHitFraction = 0.1) {
  const BruteForce brute(mesh.view());
  int hits = 0, mismatches = 0;
  for (const Ray& ray : hierarchyRays(mesh, grid, rayCount, seed)) {
    const Hit expected = brute.intersect(ray);
    const Hit got = grid.intersect(ray);
    hits += expected.found();
    const bool same = std::memcmp(&got, &expected, sizeof(Hit)) == 0;
    const bool sameOcclusion = grid.occluded(ray) == expected.found();
    if ((!same || !sameOcclusion) && ++mismatches <= 5)
      ADD_FAILURE() << accel_test::describe(ray) << ": brute force primitive " << expected.primitive << " t "
                    << expected.t << ", hgrid primitive " << got.primitive << " t " << got.t
                    << (sameOcclusion ? "" : " (occluded() disagrees)");
  }
  EXPECT_EQ(mismatches, 0);
  EXPECT_GT(hits, minimumHitFraction * rayCount);  // the rays do hit things
}

uint64_t subGridVoxels(const HierarchicalGrid& grid) {
  uint64_t count = 0;
  for (const HierarchicalGrid::Node& node : grid.nodes()) count += node.isSubGrid();
  return count;
}

TEST(HierarchicalGrid, MatchesBruteForceWithDefaults) {
  const TestMesh mesh = accel_test::mixedScene(1);
  const HierarchicalGrid grid(mesh.view());
  expectSameAsBruteForce(mesh, grid, 20000, 100);
}

TEST(HierarchicalGrid, MatchesBruteForceOnEachSceneKind) {
  std::mt19937 random(3);
  TestMesh soup, room, thin, cluster;
  accel_test::addRandomTriangles(soup, 2000, random);
  accel_test::addRoomOfBoxes(room, random);
  accel_test::addLongThinTriangles(thin, 300, random);
  accel_test::addClusterInEmptyRoom(cluster, 3000, random);
  const TestMesh hall = accel_test::furnishedHall(6000, 7);
  for (const TestMesh* mesh : std::initializer_list<const TestMesh*>{&soup, &room, &thin, &cluster, &hall}) {
    SCOPED_TRACE(std::to_string(mesh->triangleCount()) + " triangles");
    const HierarchicalGrid automatic(mesh->view());
    expectSameAsBruteForce(*mesh, automatic, 6000, 300);
    // Coarse top grid, small limit: deep hierarchies everywhere.
    const HierarchicalGrid deep(mesh->view(), HierarchicalGridOptions{4, 4, 0, 4, 2.0});
    EXPECT_GT(deep.stats().maxDepth, 1u);
    expectSameAsBruteForce(*mesh, deep, 6000, 301);
    // Fixed sub-grid resolution, as in the paper.
    const HierarchicalGrid fixed(mesh->view(), HierarchicalGridOptions{8, 16, 4, 3, 2.0});
    expectSameAsBruteForce(*mesh, fixed, 6000, 302);
  }
}

TEST(HierarchicalGrid, MatchesBruteForceAcrossParameters) {
  const TestMesh mesh = accel_test::mixedScene(2);
  const HierarchicalGridOptions cases[] = {
      {1, 1, 0, 8, 2.0},   // one top voxel, subdivided to the depth cap
      {1, 8, 2, 8, 2.0},   // binary splits, eight levels
      {3, 2, 3, 5, 2.0},   {7, 16, 0, 2, 2.0}, {16, 64, 0, 4, 2.0},
      {64, 4, 0, 3, 1.0},  {0, 1, 0, 1, 3.0},   // depth 1: a uniform grid
      {0, 100000, 0, 4, 0.1},
  };
  for (const HierarchicalGridOptions& options : cases) {
    SCOPED_TRACE("res=" + std::to_string(options.resolution) + " max=" + std::to_string(options.maxReferences) +
                 " subres=" + std::to_string(options.subResolution) + " depth=" + std::to_string(options.maxLevels));
    const HierarchicalGrid grid(mesh.view(), options);
    EXPECT_LE(grid.stats().maxDepth, uint32_t(options.maxLevels));
    expectSameAsBruteForce(mesh, grid, 3000, 200 + options.maxReferences);
  }
}

TEST(HierarchicalGrid, MatchesBruteForceFarFromTheWorldOrigin) {
  std::mt19937 random(4);
  TestMesh far;
  accel_test::addRoomOfBoxes(far, random);
  accel_test::addRandomTriangles(far, 300, random);
  accel_test::moveFarFromTheOrigin(far);
  const HierarchicalGrid grid(far.view(), HierarchicalGridOptions{4, 4, 0, 4, 2.0});
  EXPECT_GT(grid.stats().maxDepth, 1u);
  expectSameAsBruteForce(far, grid, 10000, 400);
}

TEST(HierarchicalGrid, SubdividesOnlyDenseVoxels) {
  std::mt19937 random(5);
  TestMesh cluster;
  accel_test::addClusterInEmptyRoom(cluster, 4000, random);
  const HierarchicalGrid grid(cluster.view(), HierarchicalGridOptions{8, 32, 0, 4, 2.0});
  const AcceleratorStats& stats = grid.stats();
  EXPECT_GE(stats.maxDepth, 2u);
  EXPECT_GT(grid.grids().size(), 1u);
  EXPECT_EQ(grid.grids()[0].resolution, (std::array<int, 3>{8, 6, 2}));
  // Every sub-grid hangs from exactly one voxel, and lies inside it.
  EXPECT_EQ(subGridVoxels(grid), grid.grids().size() - 1);
  for (size_t g = 1; g < grid.grids().size(); ++g) {
    const auto& record = grid.grids()[g];
    EXPECT_GE(record.level, 2u);
    EXPECT_LE(record.level, stats.maxDepth);
  }
  // The empty room stays coarse: most top voxels are empty leaves.
  EXPECT_GT(stats.emptyLeaves, 0u);
  expectSameAsBruteForce(cluster, grid, 8000, 500, 0.5);

  // No sub-grids when no voxel is over the limit.
  const HierarchicalGrid flat(cluster.view(), HierarchicalGridOptions{8, 1 << 24, 0, 4, 2.0});
  EXPECT_EQ(flat.grids().size(), 1u);
  EXPECT_EQ(flat.stats().maxDepth, 1u);
  EXPECT_EQ(flat.stats().averageDepth, 1.0);
}

TEST(HierarchicalGrid, DepthOneIsTheUniformGrid) {
  const TestMesh mesh = accel_test::mixedScene(6);
  const HierarchicalGrid hierarchical(mesh.view(), HierarchicalGridOptions{20, 1, 0, 1, 3.0});
  const UniformGrid uniform(mesh.view(), UniformGridOptions{20});
  EXPECT_EQ(hierarchical.grids().size(), 1u);
  EXPECT_EQ(hierarchical.grids()[0].resolution, uniform.resolution());
  EXPECT_EQ(hierarchical.stats().nodes, uniform.stats().nodes);
  EXPECT_EQ(hierarchical.stats().leaves, uniform.stats().leaves);
  EXPECT_EQ(hierarchical.stats().triangleReferences, uniform.stats().triangleReferences);
}

TEST(HierarchicalGrid, ReportsStatistics) {
  std::mt19937 random(7);
  TestMesh mesh;
  accel_test::addClusterInEmptyRoom(mesh, 2000, random);
  accel_test::addRandomTriangles(mesh, 200, random);
  const HierarchicalGrid grid(mesh.view(), HierarchicalGridOptions{6, 16, 0, 3, 2.0}, "hgrid:res=6,max=16,depth=3");
  const AcceleratorStats& stats = grid.stats();
  EXPECT_EQ(stats.spec, "hgrid:res=6,max=16,depth=3");
  EXPECT_EQ(stats.nodes, grid.nodes().size());
  EXPECT_EQ(stats.leaves + stats.emptyLeaves + subGridVoxels(grid), stats.nodes);
  EXPECT_GT(stats.leaves, 0u);
  EXPECT_GE(stats.triangleReferences, mesh.triangleCount());
  EXPECT_EQ(stats.maxDepth, 3u);
  EXPECT_GT(stats.averageDepth, 1.0);
  EXPECT_LE(stats.averageDepth, 3.0);
  EXPECT_GE(stats.bytes, stats.nodes * sizeof(HierarchicalGrid::Node) + stats.triangleReferences * sizeof(uint32_t));
  EXPECT_GE(stats.buildMs, 0.0);
  // Leaves point into the reference array, sub-grids into the grid records.
  uint64_t referenced = 0;
  for (const HierarchicalGrid::Node& node : grid.nodes()) {
    if (node.isSubGrid()) {
      EXPECT_LT(node.first, grid.grids().size());
    } else {
      EXPECT_LE(uint64_t(node.first) + node.count, stats.triangleReferences);
      referenced += node.count;
    }
  }
  EXPECT_EQ(referenced, stats.triangleReferences);
}

TEST(HierarchicalGrid, HandlesFlatBoundsEmptyMeshesAndBadRays) {
  TestMesh floor;
  accel_test::addFloor(floor);
  const HierarchicalGrid grid(floor.view(), HierarchicalGridOptions{2, 8, 0, 4, 2.0});
  EXPECT_EQ(grid.grids()[0].resolution[2], 1);
  expectSameAsBruteForce(floor, grid, 8000, 500, 0.05);
  const Hit hit = grid.intersect(Ray{{5, 5, 3}, {0, 0, -1}});
  ASSERT_TRUE(hit.found());
  EXPECT_EQ(hit.t, 2.0f);
  EXPECT_EQ(hit.primitive, BruteForce(floor.view()).intersect(Ray{{5, 5, 3}, {0, 0, -1}}).primitive);

  const TestMesh empty;
  const HierarchicalGrid emptyGrid(empty.view());
  EXPECT_FALSE(emptyGrid.intersect(Ray{{0, 0, 0}, {1, 0, 0}}).found());
  EXPECT_FALSE(emptyGrid.occluded(Ray{{0, 0, 0}, {1, 0, 0}}));
  EXPECT_TRUE(emptyGrid.bounds().empty());
  EXPECT_EQ(emptyGrid.stats().nodes, 0u);

  TestMesh point;  // only degenerate triangles, all at one point
  for (int i = 0; i < 100; ++i) point.addTriangle({2, 2, 2}, {2, 2, 2}, {2, 2, 2});
  const HierarchicalGrid pointGrid(point.view(), HierarchicalGridOptions{0, 1, 0, 8, 2.0});
  EXPECT_FALSE(pointGrid.intersect(Ray{{0, 0, 0}, {1, 1, 1}}).found());
  EXPECT_FALSE(pointGrid.occluded(Ray{{0, 0, 0}, {1, 1, 1}}));

  const TestMesh mesh = accel_test::mixedScene(8);
  const HierarchicalGrid mixed(mesh.view());
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (const Ray& ray : {Ray{{5, 5, 5}, {0, 0, 0}}, Ray{{nan, 5, 5}, {1, 0, 0}}, Ray{{5, 5, 5}, {1, nan, 0}},
                         Ray{{5, 5, 5}, {1, 0, 0}, 2.0f, 1.0f}}) {
    EXPECT_FALSE(mixed.intersect(ray).found());
    EXPECT_FALSE(mixed.occluded(ray));
  }
}

TEST(HierarchicalGrid, AnswersFromManyThreadsAtOnce) {
  const TestMesh mesh = accel_test::furnishedHall(20000, 9);
  const HierarchicalGrid grid(mesh.view());
  const std::vector<Ray> rays = hierarchyRays(mesh, grid, 4000, 900);
  const auto same = [](const Hit& a, const Hit& b) { return std::memcmp(&a, &b, sizeof(Hit)) == 0; };
  for (int count : accel_test::mismatchesFromManyThreads(grid, rays, 2, same)) EXPECT_EQ(count, 0);
}

// ---------------------------------------------------------------------------
// Specs

std::string buildError(const TestMesh& mesh, const char* text) {
  try {
    buildAccelerator(parseAcceleratorSpec(text), mesh.view());
  } catch (const std::invalid_argument& error) {
    return error.what();
  }
  return "(no error)";
}

TEST(HierarchicalGridSpec, BuildsFromSpecs) {
  const TestMesh mesh = accel_test::mixedScene(10);
  const auto grid = buildAccelerator(parseAcceleratorSpec("hgrid:res=16,max=64"), mesh.view());
  EXPECT_EQ(grid->stats().spec, "hgrid:res=16,max=64");
  const auto& hierarchical = static_cast<const HierarchicalGrid&>(*grid);
  EXPECT_EQ(hierarchical.grids()[0].resolution[0], 16);
  const auto automatic = buildAccelerator(parseAcceleratorSpec("hgrid"), mesh.view());
  const auto all = buildAccelerator(parseAcceleratorSpec("hgrid:res=4,max=2,subres=3,depth=6,density=1.5"),
                                    mesh.view());
  EXPECT_GT(all->stats().maxDepth, 2u);
  const BruteForce brute(mesh.view());
  for (const Ray& ray : accel_test::testRays(mesh, 3000, 11)) {
    const Hit expected = brute.intersect(ray);
    for (const Accelerator* accelerator : {grid.get(), automatic.get(), all.get()}) {
      const Hit hit = accelerator->intersect(ray);
      ASSERT_EQ(std::memcmp(&hit, &expected, sizeof(Hit)), 0) << accel_test::describe(ray);
    }
  }
  EXPECT_NO_THROW(validateAcceleratorSpec(parseAcceleratorSpec("hgrid:res=16,max=64,subres=8,depth=3")));
}

TEST(HierarchicalGridSpec, RejectsBadParametersNamingThem) {
  const TestMesh mesh = accel_test::mixedScene(12);
  EXPECT_EQ(buildError(mesh, "hgrid:max=0"),
            "accelerator spec 'hgrid:max=0': parameter max must be a positive integer (got '0')");
  EXPECT_EQ(buildError(mesh, "hgrid:depth=9"),
            "accelerator spec 'hgrid:depth=9': parameter depth must be at most 8 (got 9)");
  EXPECT_EQ(buildError(mesh, "hgrid:subres=1"),
            "accelerator spec 'hgrid:subres=1': parameter subres must be an integer >= 2 (got '1')");
  EXPECT_EQ(buildError(mesh, "hgrid:res=600"),
            "accelerator spec 'hgrid:res=600': parameter res must be at most 512 (got 600)");
  EXPECT_NE(buildError(mesh, "hgrid:density=0").find("density must be a positive number"), std::string::npos);
  EXPECT_EQ(buildError(mesh, "hgrid:maximum=4"),
            "accelerator spec 'hgrid:maximum=4': unknown parameter 'maximum' for hgrid "
            "(it takes: res, max, subres, depth, density, subdensity)");
  EXPECT_EQ(buildError(mesh, "hgrid:sah"), "accelerator spec 'hgrid:sah': hgrid takes no variant (got 'sah')");
  EXPECT_THROW(validateAcceleratorSpec(parseAcceleratorSpec("hgrid:max=abc")), std::invalid_argument);
  bool listed = false;
  for (std::string_view kind : acceleratorKinds()) listed |= kind == "hgrid";
  EXPECT_TRUE(listed);
}

}  // namespace
}  // namespace portico
