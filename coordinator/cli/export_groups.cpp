#include "coordinator/cli/export_groups.h"

#include <map>
#include <string>

#include "common/scene/import/quad_light.h"

namespace portico::cli {

namespace {

bool formParallelogram(const MeshView& mesh, uint32_t first) {
  Vec3 v[6];
  mesh.triangle(first, v[0], v[1], v[2]);
  mesh.triangle(first + 1, v[3], v[4], v[5]);
  std::vector<float> positions;
  for (const Vec3& p : v) positions.insert(positions.end(), {p.x, p.y, p.z});
  std::string problem;
  return parallelogramFromTriangles(positions, {0, 1, 2, 3, 4, 5}, problem).has_value();
}

}  // namespace

std::vector<TriangleGroup> exportGroups(const CellGeometry& geometry, const std::vector<Material>& materials) {
  const MeshView& mesh = geometry.mesh();
  std::map<uint32_t, std::vector<uint32_t>> byMaterial;
  std::vector<TriangleGroup> lamps;
  for (uint32_t t = 0; t < mesh.triangleCount; ++t) {
    const uint32_t material = geometry.material(t);
    if (!materials[material].emissive()) {
      byMaterial[material].push_back(t);
    } else if (t + 1 < mesh.triangleCount && geometry.material(t + 1) == material && formParallelogram(mesh, t)) {
      lamps.push_back({material, {t, t + 1}, true});
      ++t;
    } else {
      lamps.push_back({material, {t}, true});
    }
  }
  std::vector<TriangleGroup> groups;
  for (auto& [material, triangles] : byMaterial) groups.push_back({material, std::move(triangles), false});
  groups.insert(groups.end(), lamps.begin(), lamps.end());
  return groups;
}

}  // namespace portico::cli
