#include "common/accel/brute_force.h"

#include <chrono>

#include "common/accel/triangle_intersect.h"

namespace portico {

BruteForce::BruteForce(const MeshView& mesh, std::string_view spec) : mesh_(mesh) {
  const auto start = std::chrono::steady_clock::now();
  for (uint32_t primitive = 0; primitive < mesh.triangleCount; ++primitive)
    bounds_.extend(mesh.triangleBounds(primitive));
  stats_.spec = std::string(spec);
  // One leaf holding everything: depth 1, like a grid of one voxel.
  stats_.nodes = 1;
  stats_.leaves = mesh.triangleCount > 0 ? 1 : 0;
  stats_.emptyLeaves = mesh.triangleCount > 0 ? 0 : 1;
  stats_.triangleReferences = mesh.triangleCount;
  stats_.averageDepth = 1;
  stats_.maxDepth = 1;
  stats_.bytes = sizeof(*this);
  stats_.buildMs =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

Hit BruteForce::intersect(const Ray& ray) const {
  Hit best;
  if (!hasFiniteOriginAndDirection(ray)) return best;
  const WatertightRay frame(ray.direction);
  const uint32_t count = static_cast<uint32_t>(mesh_.triangleCount);
  for (uint32_t primitive = 0; primitive < count; ++primitive) {
    Vec3 v0, v1, v2;
    mesh_.triangle(primitive, v0, v1, v2);
    float t, u, v;
    if (intersectTriangle(frame, ray, v0, v1, v2, t, u, v) && closerThan(t, primitive, best))
      best = Hit{t, primitive, u, v};
  }
  return best;
}

bool BruteForce::occluded(const Ray& ray) const {
  if (!hasFiniteOriginAndDirection(ray)) return false;
  const WatertightRay frame(ray.direction);
  const uint32_t count = static_cast<uint32_t>(mesh_.triangleCount);
  for (uint32_t primitive = 0; primitive < count; ++primitive) {
    Vec3 v0, v1, v2;
    mesh_.triangle(primitive, v0, v1, v2);
    float t, u, v;
    if (intersectTriangle(frame, ray, v0, v1, v2, t, u, v)) return true;
  }
  return false;
}

}  // namespace portico
