#include "common/scene/import/quad_light.h"

#include <fmt/format.h>

#include <array>

namespace portico {

std::optional<Parallelogram> parallelogramFromTriangles(const std::vector<float>& positions,
                                                        const std::vector<uint32_t>& indices, std::string& problem) {
  const size_t triangles = indices.size() / 3;
  if (triangles != 2) {
    problem = fmt::format("{} triangle{}", triangles, triangles == 1 ? "" : "s");
    return std::nullopt;
  }
  std::array<Vec3, 6> v;
  Bounds3 box;
  for (int i = 0; i < 6; ++i) {
    const size_t index = indices[i];
    v[i] = Vec3(positions[3 * index], positions[3 * index + 1], positions[3 * index + 2]);
    box.extend(v[i]);
  }
  const float size = maxComponent(box.diagonal());
  const float tolerance = 1e-4f * size;
  const Vec3 normalA = cross(v[1] - v[0], v[2] - v[0]);
  const Vec3 normalB = cross(v[4] - v[3], v[5] - v[3]);
  if (!(length(normalA) > 1e-8f * size * size) || !(length(normalB) > 1e-8f * size * size)) {
    problem = "2 triangles, one of them degenerate";
    return std::nullopt;
  }
  // Which corners of the first triangle reappear in the second.
  std::array<int, 3> partner{-1, -1, -1};
  int shared = 0;
  for (int a = 0; a < 3; ++a)
    for (int b = 3; b < 6; ++b)
      if (partner[a] < 0 && length(v[a] - v[b]) <= tolerance) {
        partner[a] = b;
        ++shared;
      }
  if (shared != 2) {
    problem = fmt::format("2 triangles sharing {} corners instead of a diagonal", shared);
    return std::nullopt;
  }
  int lone = 0;
  while (partner[lone] >= 0) ++lone;
  int otherLone = 3;
  while (otherLone == partner[0] || otherLone == partner[1] || otherLone == partner[2]) ++otherLone;
  const Vec3& r = v[lone];
  const Vec3& p = v[(lone + 1) % 3];
  const Vec3& q = v[(lone + 2) % 3];
  const Vec3& s = v[otherLone];
  // A parallelogram: the diagonals (p, q) and (r, s) bisect each other.
  if (length((r + s) - (p + q)) > 2.0f * tolerance) {
    problem = "2 triangles that do not form a parallelogram";
    return std::nullopt;
  }
  if (dot(normalA, normalB) <= 0.0f) {
    problem = "2 triangles facing opposite ways";
    return std::nullopt;
  }
  // (r, p, q) is the first triangle in its own order, so cross(p - r, q - r)
  // has its winding: the emitting side.
  return Parallelogram{r, p - r, q - r};
}

}  // namespace portico
