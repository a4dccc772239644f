// Voxel cells: the grid's planes, portal rectangles, light pieces, and the
// triangles binned per voxel (binned_cells.h).
#include "common/scene/import/voxel_cells.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "common/scene/import/binned_cells.h"
#include "common/triangle_box_overlap.h"

namespace portico {

namespace {

// The one axis `edge` runs along, or -1 when it is oblique (components other
// than the largest must be below a millionth of it).
int alignedAxis(const Vec3& edge) {
  int axis = 0;
  for (int a = 1; a < 3; ++a)
    if (std::abs(edge[a]) > std::abs(edge[axis])) axis = a;
  const float size = std::abs(edge[axis]);
  if (!(size > 0.0f)) return -1;
  for (int a = 0; a < 3; ++a)
    if (a != axis && std::abs(edge[a]) > 1e-6f * size) return -1;
  return axis;
}

// The edge's extent along `axis` cut at the grid's inner planes: the cut
// points from the edge's start to its end (signed direction kept).
std::vector<float> cutPoints(const VoxelGrid& grid, int axis, float start, float end) {
  const float lo = std::min(start, end), hi = std::max(start, end);
  std::vector<float> points{lo};
  for (uint32_t k = 1; k < grid.resolution(); ++k)
    if (grid.boundary(axis, k) > lo && grid.boundary(axis, k) < hi) points.push_back(grid.boundary(axis, k));
  points.push_back(hi);
  if (end < start) std::reverse(points.begin(), points.end());
  return points;
}

template <typename Visit>
void forEachTouchedVoxel(const VoxelGrid& grid, const ImportedObject& object, size_t triangle, Visit&& visit) {
  const uint32_t* corners = &object.indices[3 * triangle];
  const Vec3 a = object.vertex(corners[0]), b = object.vertex(corners[1]), c = object.vertex(corners[2]);
  const Vec3 lo = min(a, min(b, c)), hi = max(a, max(b, c));
  const float tolerance = grid.overlapTolerance();
  std::array<uint32_t, 3> first{}, last{};
  for (int axis = 0; axis < 3; ++axis)
    grid.touchedSlabs(axis, lo[axis] - tolerance, hi[axis] + tolerance, first[axis], last[axis]);
  for (uint32_t z = first[2]; z <= last[2]; ++z)
    for (uint32_t y = first[1]; y <= last[1]; ++y)
      for (uint32_t x = first[0]; x <= last[0]; ++x) {
        const uint32_t cell = grid.cellId(x, y, z);
        if (triangleOverlapsBox(a, b, c, grid.cellBounds(cell), tolerance)) visit(cell);
      }
}

void addGridPortals(const VoxelGrid& grid, SceneStoreWriter& writer) {
  const uint32_t n = grid.resolution();
  for (int axis = 0; axis < 3; ++axis) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    for (uint32_t k = 1; k < n; ++k)
      for (uint32_t j = 0; j < n; ++j)
        for (uint32_t i = 0; i < n; ++i) {
          std::array<uint32_t, 3> below{}, above{};
          below[axis] = k - 1;
          above[axis] = k;
          below[u] = above[u] = i;
          below[v] = above[v] = j;
          auto point = [&](uint32_t du, uint32_t dv) {
            Vec3 p;
            p[axis] = grid.boundary(axis, k);
            p[u] = grid.boundary(u, i + du);
            p[v] = grid.boundary(v, j + dv);
            return p;
          };
          writer.addPortal(grid.cellId(below[0], below[1], below[2]), grid.cellId(above[0], above[1], above[2]),
                           {point(0, 0), point(1, 0), point(1, 1), point(0, 1)});
        }
  }
}

}  // namespace

VoxelGrid::VoxelGrid(const Bounds3& bounds, uint32_t resolution) : resolution_(resolution) {
  if (resolution == 0 || resolution > 1024) throw std::invalid_argument("voxel grid: resolution must be in [1, 1024]");
  if (!isFinite(bounds.lo) || !isFinite(bounds.hi) || !(bounds.lo.x < bounds.hi.x) || !(bounds.lo.y < bounds.hi.y) ||
      !(bounds.lo.z < bounds.hi.z))
    throw std::invalid_argument("voxel grid: bounds must be finite with a positive extent on every axis");
  for (int axis = 0; axis < 3; ++axis) {
    std::vector<float>& planes = boundaries_[axis];
    planes.resize(resolution + 1);
    const double lo = bounds.lo[axis], hi = bounds.hi[axis];
    for (uint32_t k = 0; k <= resolution; ++k) planes[k] = static_cast<float>(lo + (hi - lo) * k / resolution);
    planes.front() = bounds.lo[axis];
    planes.back() = bounds.hi[axis];
  }
  tolerance_ = 1e-5f * maxComponent(bounds.diagonal());
}

std::array<uint32_t, 3> VoxelGrid::coordinates(uint32_t cell) const {
  return {cell % resolution_, (cell / resolution_) % resolution_, cell / (resolution_ * resolution_)};
}

std::string VoxelGrid::cellName(const std::array<uint32_t, 3>& c) {
  return fmt::format("voxel-{}-{}-{}", c[0], c[1], c[2]);
}

Bounds3 VoxelGrid::cellBounds(uint32_t cell) const {
  const std::array<uint32_t, 3> c = coordinates(cell);
  Bounds3 box;
  for (int axis = 0; axis < 3; ++axis) {
    box.lo[axis] = boundaries_[axis][c[axis]];
    box.hi[axis] = boundaries_[axis][c[axis] + 1];
  }
  return box;
}

uint32_t VoxelGrid::slab(int axis, float value) const {
  const std::vector<float>& planes = boundaries_[axis];
  // The first inner plane above `value`, minus one: the slab [b_k, b_k+1) holding it.
  const auto above = std::upper_bound(planes.begin() + 1, planes.end() - 1, value);
  return static_cast<uint32_t>(above - (planes.begin() + 1));
}

uint32_t VoxelGrid::locate(const Vec3& p) const { return cellId(slab(0, p.x), slab(1, p.y), slab(2, p.z)); }

void VoxelGrid::touchedSlabs(int axis, float lo, float hi, uint32_t& first, uint32_t& last) const {
  const std::vector<float>& planes = boundaries_[axis];
  // Slab k spans [b_k, b_k+1]: first = the first k with b_k+1 >= lo, last = the last with b_k <= hi.
  first = static_cast<uint32_t>(std::lower_bound(planes.begin() + 1, planes.end() - 1, lo) - (planes.begin() + 1));
  const auto afterLast = std::upper_bound(planes.begin() + 1, planes.end() - 1, hi);
  last = static_cast<uint32_t>(afterLast - (planes.begin() + 1));
  first = std::min(first, resolution_ - 1);
  last = std::max(first, std::min(last, resolution_ - 1));
}

std::vector<AreaLight> voxelLights(const ImportedLight& light, const VoxelGrid& grid) {
  const Parallelogram& shape = light.shape;
  const Vec3 normal = normalize(cross(shape.edge1, shape.edge2));
  const int axis1 = alignedAxis(shape.edge1), axis2 = alignedAxis(shape.edge2);
  std::vector<AreaLight> lights;
  if (light.kind == LightShape::Point) {   // in the voxel holding its point
    AreaLight whole = light.areaLight();
    whole.cell = grid.locate(whole.corner);
    lights.push_back(whole);
    return lights;
  }
  if (light.kind == LightShape::Triangle || axis1 < 0 || axis2 < 0 || axis1 == axis2) {
    // A triangle, or oblique: whole, in the voxel holding its centre (nudged to the emitting side).
    AreaLight whole = light.areaLight();
    whole.cell = grid.locate(whole.center() + normal * grid.overlapTolerance());
    lights.push_back(whole);
    return lights;
  }
  const int normalAxis = 3 - axis1 - axis2;
  // The slab along the normal: a light lying on a voxel plane belongs to the
  // slab it shines into.
  const float planeValue = shape.corner[normalAxis] + normal[normalAxis] * grid.overlapTolerance();
  const uint32_t normalSlab = grid.slab(normalAxis, planeValue);
  const std::vector<float> cuts1 =
      cutPoints(grid, axis1, shape.corner[axis1], shape.corner[axis1] + shape.edge1[axis1]);
  const std::vector<float> cuts2 =
      cutPoints(grid, axis2, shape.corner[axis2], shape.corner[axis2] + shape.edge2[axis2]);
  for (size_t j = 0; j + 1 < cuts2.size(); ++j)
    for (size_t i = 0; i + 1 < cuts1.size(); ++i) {
      AreaLight piece;
      piece.corner = shape.corner;
      piece.corner[axis1] = cuts1[i];
      piece.corner[axis2] = cuts2[j];
      piece.edge1 = Vec3(0.0f);
      piece.edge1[axis1] = cuts1[i + 1] - cuts1[i];
      piece.edge2 = Vec3(0.0f);
      piece.edge2[axis2] = cuts2[j + 1] - cuts2[j];
      piece.radiance = light.radiance;
      std::array<uint32_t, 3> cell{};
      cell[axis1] = grid.slab(axis1, 0.5f * (cuts1[i] + cuts1[i + 1]));
      cell[axis2] = grid.slab(axis2, 0.5f * (cuts2[j] + cuts2[j + 1]));
      cell[normalAxis] = normalSlab;
      piece.cell = grid.cellId(cell[0], cell[1], cell[2]);
      lights.push_back(piece);
    }
  return lights;
}

void writeVoxelCells(const ImportedScene& scene, const VoxelGrid& grid, SceneStoreWriter& writer) {
  addGridPortals(grid, writer);
  for (const ImportedLight& light : scene.lights)
    for (const AreaLight& piece : voxelLights(light, grid)) writer.addLight(piece);
  for (size_t k = 0; k < scene.cameras.size(); ++k) {
    Camera camera = scene.cameras[k];
    camera.cell = grid.locate(camera.origin);
    if (k == 0)
      writer.setCamera(camera);
    else
      writer.addCamera(camera);
  }

  writeBinnedCells(
      scene, grid.cellCount(),
      [&](const ImportedObject& object, size_t triangle, const std::function<void(uint32_t)>& visit) {
        forEachTouchedVoxel(grid, object, triangle, visit);
      },
      [&](uint32_t id) { return VoxelGrid::cellName(grid.coordinates(id)); },
      [&](uint32_t id) { return grid.cellBounds(id); }, writer);
}

}  // namespace portico
