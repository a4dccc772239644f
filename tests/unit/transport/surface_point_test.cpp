#include "common/transport/surface_point.h"

#include <gtest/gtest.h>

namespace portico {
namespace {

// Two walls of a room meeting at the corner x = 4, z = 0: the back wall
// (z = 0, x in [0, 4]) as one triangle.
const float kPositions[] = {0, 0, 0, 4, 0, 0, 4, 3, 0};
const uint32_t kIndices[] = {0, 1, 2};
const MeshView kBackWall{kPositions, 3, kIndices, 1, 0};

TEST(SurfacePoint, AHitInsideTheTriangleIsItsBarycentricPoint) {
  const Vec3 p = interiorHitPoint(kBackWall, 0, 0.5f, 0.25f);
  // v0 + 0.5 (4, 0, 0) + 0.25 (4, 3, 0), moved at most 2e-5 * 4.
  EXPECT_NEAR(p.x, 3.0f, 1e-4f);
  EXPECT_NEAR(p.y, 0.75f, 1e-4f);
  EXPECT_EQ(p.z, 0.0f);
}

TEST(SurfacePoint, AHitOnTheEdgeAtAWallCornerStartsStrictlyInside) {
  // u + v = 1, v = 0.5: on the edge x = 4 shared with the side wall, where a
  // bounce heading into the side wall started on its plane and passed through.
  for (float v : {0.0f, 0.5f, 1.0f}) {
    const Vec3 p = interiorHitPoint(kBackWall, 0, 1.0f - v, v);
    EXPECT_LT(p.x, 4.0f) << "v = " << v;
    EXPECT_GT(p.x, 4.0f - 1e-3f) << "v = " << v;
  }
}

TEST(SurfacePoint, ADegenerateTriangleGivesItsPoint) {
  const float line[] = {1, 1, 1, 1, 1, 1, 1, 1, 1};
  const MeshView point{line, 3, kIndices, 1, 0};
  EXPECT_EQ(interiorHitPoint(point, 0, 0.3f, 0.3f), Vec3(1, 1, 1));
}

}  // namespace
}  // namespace portico
