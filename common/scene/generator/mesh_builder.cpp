#include "common/scene/generator/mesh_builder.h"

#include <algorithm>
#include <stdexcept>

namespace portico {

namespace {

// Sorted, distinct split values of one in-plane coordinate, clipped to [lo, hi].
std::vector<float> splitValues(float lo, float hi, const std::vector<PlaneRect>& holes, bool alongU) {
  std::vector<float> values{lo, hi};
  for (const PlaneRect& hole : holes) {
    const float edges[2] = {alongU ? hole.u0 : hole.v0, alongU ? hole.u1 : hole.v1};
    for (float value : edges)
      if (value > lo && value < hi) values.push_back(value);
  }
  std::sort(values.begin(), values.end());
  values.erase(std::unique(values.begin(), values.end()), values.end());
  return values;
}

bool insideAnyHole(float u, float v, const std::vector<PlaneRect>& holes) {
  for (const PlaneRect& hole : holes)
    if (u > hole.u0 && u < hole.u1 && v > hole.v0 && v < hole.v1) return true;
  return false;
}

}  // namespace

uint32_t MeshBuilder::addVertex(const Vec3& p) {
  const auto index = static_cast<uint32_t>(positions_.size() / 3);
  positions_.insert(positions_.end(), {p.x, p.y, p.z});
  return index;
}

void MeshBuilder::addTriangle(uint32_t a, uint32_t b, uint32_t c, uint32_t material) {
  indices_.insert(indices_.end(), {a, b, c});
  materials_.push_back(material);
}

void MeshBuilder::addAxisRectangle(int axis, float value, bool facesPositive, const PlaneRect& rect,
                                   uint32_t material, const std::vector<PlaneRect>& holes) {
  if (axis < 0 || axis > 2 || !(rect.u0 < rect.u1) || !(rect.v0 < rect.v1))
    throw std::invalid_argument("MeshBuilder::addAxisRectangle: bad axis or empty rectangle");
  const int uAxis = (axis + 1) % 3;
  const int vAxis = (axis + 2) % 3;
  const std::vector<float> us = splitValues(rect.u0, rect.u1, holes, true);
  const std::vector<float> vs = splitValues(rect.v0, rect.v1, holes, false);

  // Grid vertices, shared by the quads around them.
  std::vector<uint32_t> grid(us.size() * vs.size());
  for (size_t j = 0; j < vs.size(); ++j)
    for (size_t i = 0; i < us.size(); ++i) {
      Vec3 p;
      p[axis] = value;
      p[uAxis] = us[i];
      p[vAxis] = vs[j];
      grid[j * us.size() + i] = addVertex(p);
    }
  // cross(e_u, e_v) = e_axis for cyclic (axis, u, v): counter-clockwise in
  // (u, v) faces +axis.
  for (size_t j = 0; j + 1 < vs.size(); ++j)
    for (size_t i = 0; i + 1 < us.size(); ++i) {
      if (insideAnyHole(0.5f * (us[i] + us[i + 1]), 0.5f * (vs[j] + vs[j + 1]), holes)) continue;
      const uint32_t a = grid[j * us.size() + i], b = grid[j * us.size() + i + 1];
      const uint32_t c = grid[(j + 1) * us.size() + i + 1], d = grid[(j + 1) * us.size() + i];
      if (facesPositive) {
        addTriangle(a, b, c, material);
        addTriangle(a, c, d, material);
      } else {
        addTriangle(a, c, b, material);
        addTriangle(a, d, c, material);
      }
    }
}

void MeshBuilder::addBox(const Bounds3& box, uint32_t material, bool withBottom) {
  for (int axis = 0; axis < 3; ++axis) {
    const int uAxis = (axis + 1) % 3;
    const int vAxis = (axis + 2) % 3;
    const PlaneRect face{box.lo[uAxis], box.hi[uAxis], box.lo[vAxis], box.hi[vAxis]};
    if (axis != 1 || withBottom) addAxisRectangle(axis, box.lo[axis], false, face, material);
    addAxisRectangle(axis, box.hi[axis], true, face, material);
  }
}

void MeshBuilder::addParallelogram(const Vec3& corner, const Vec3& edge1, const Vec3& edge2, uint32_t material) {
  const uint32_t a = addVertex(corner);
  const uint32_t b = addVertex(corner + edge1);
  const uint32_t c = addVertex(corner + edge1 + edge2);
  const uint32_t d = addVertex(corner + edge2);
  // Both triangles have normal cross(edge1, edge2): (a, b, c) gives
  // cross(edge1, edge1 + edge2) and (a, c, d) cross(edge1 + edge2, edge2).
  addTriangle(a, b, c, material);
  addTriangle(a, c, d, material);
}

void MeshBuilder::addSurface(int columns, int rows, bool wrapS, const std::function<Vec3(float, float)>& point,
                             uint32_t material) {
  if (columns < 1 || rows < 1 || (wrapS && columns < 3))
    throw std::invalid_argument("MeshBuilder::addSurface: too few columns or rows");
  const int distinctColumns = wrapS ? columns : columns + 1;
  const uint32_t first = static_cast<uint32_t>(positions_.size() / 3);
  for (int j = 0; j <= rows; ++j)
    for (int i = 0; i < distinctColumns; ++i) addVertex(point(float(i) / float(columns), float(j) / float(rows)));
  const auto at = [&](int i, int j) { return first + uint32_t(j * distinctColumns + (i % distinctColumns)); };
  for (int j = 0; j < rows; ++j)
    for (int i = 0; i < columns; ++i) {
      addTriangle(at(i, j), at(i + 1, j), at(i + 1, j + 1), material);
      addTriangle(at(i, j), at(i + 1, j + 1), at(i, j + 1), material);
    }
}

void MeshBuilder::moveInto(CellContent& cell) {
  cell.positions = std::move(positions_);
  cell.indices = std::move(indices_);
  cell.materials = std::move(materials_);
  positions_.clear();
  indices_.clear();
  materials_.clear();
}

}  // namespace portico
