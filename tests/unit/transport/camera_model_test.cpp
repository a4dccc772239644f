#include "common/transport/camera_model.h"

#include <gtest/gtest.h>

namespace portico {
namespace {

TEST(CameraModel, FollowsTheReferenceConventions) {
  Camera camera;
  camera.origin = {0, 1, 1.95f};
  camera.target = {0, 1, -1};
  camera.up = {0, 1, 0};
  camera.fovYDegrees = 90;
  CameraModel model(camera, 200, 100);
  const Vec3 center = model.direction(100, 50);
  EXPECT_NEAR(center.z, -1, 1e-6);
  // Top edge of the image is 45 degrees up (full vertical fov 90).
  const Vec3 top = model.direction(100, 0);
  EXPECT_NEAR(top.y, std::sqrt(0.5f), 1e-5);
  // Row 0 is the top: y decreases with the row.
  EXPECT_GT(model.direction(100, 10).y, model.direction(100, 90).y);
  // x grows to the right = cross(forward, up) = +x when looking down -z.
  EXPECT_GT(model.direction(190, 50).x, 0);
  // Square pixels: horizontal tangent is aspect * vertical tangent.
  const Vec3 right = model.direction(200, 50);
  EXPECT_NEAR(right.x / -right.z, 2.0f, 1e-5);
}

}  // namespace
}  // namespace portico
