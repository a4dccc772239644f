#include "common/scene/store/mesh_slice.h"

namespace portico {

namespace {

// Where the edge a-b crosses y = height, for corners on opposite sides.
void crossing(const Vec3& a, const Vec3& b, float height, float& x, float& z) {
  const float s = (height - a.y) / (b.y - a.y);
  x = a.x + (b.x - a.x) * s;
  z = a.z + (b.z - a.z) * s;
}

}  // namespace

void sliceMesh(const MeshView& mesh, float height, std::vector<PlanSegment>& segments) {
  for (uint32_t t = 0; t < mesh.triangleCount; ++t) {
    Vec3 v[3];
    mesh.triangle(t, v[0], v[1], v[2]);
    // A corner exactly on the plane counts as above: each crossing edge
    // then has one corner strictly below, and a triangle gives 0 or 2 points.
    bool above[3];
    for (int i = 0; i < 3; ++i) above[i] = v[i].y >= height;
    if (above[0] == above[1] && above[1] == above[2]) continue;
    float xs[2], zs[2];
    int found = 0;
    for (int i = 0; i < 3 && found < 2; ++i) {
      const Vec3 &a = v[i], &b = v[(i + 1) % 3];
      if (above[i] != above[(i + 1) % 3]) crossing(a, b, height, xs[found], zs[found]), ++found;
    }
    if (found == 2) segments.push_back({xs[0], zs[0], xs[1], zs[1]});
  }
}

}  // namespace portico
