// Builds a cell's triangles from axis-aligned rectangles, boxes and
// parallelograms, for generators and importers of box-like buildings.
// Winding convention (the scene store's): a triangle's front is the side of
// cross(v1 - v0, v2 - v0).
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "common/math.h"
#include "common/scene/store/scene_store.h"

namespace portico {

// A rectangle in the two in-plane coordinates (u, v) of an axis-aligned
// plane; see MeshBuilder::addAxisRectangle for which axes u and v are.
struct PlaneRect {
  float u0 = 0, u1 = 0, v0 = 0, v1 = 0;
};

class MeshBuilder {
 public:
  // The rectangle [r.u0, r.u1] x [r.v0, r.v1] in the plane where coordinate
  // `axis` equals `value`, facing +axis (facesPositive) or -axis. In-plane
  // coordinates are cyclic: u is axis (axis+1)%3 and v is (axis+2)%3, so for
  // a wall z = c, u is x and v is y; for a floor y = c, u is z and v is x.
  // Holes (door openings) are cut out exactly: the rectangle is split along
  // every hole edge into a grid whose vertices are shared, so the pieces meet
  // without T-junctions and the hole's edges are exactly the given values.
  void addAxisRectangle(int axis, float value, bool facesPositive, const PlaneRect& rect, uint32_t material,
                        const std::vector<PlaneRect>& holes = {});
  // An axis-aligned box with outward-facing sides. A box standing on the
  // floor has no bottom face (nobody sees it); a raised one (a table top)
  // needs it.
  void addBox(const Bounds3& box, uint32_t material, bool withBottom);
  // The parallelogram corner + s*edge1 + t*edge2 as two triangles whose
  // front is the side of cross(edge1, edge2) (the convention of AreaLight).
  void addParallelogram(const Vec3& corner, const Vec3& edge1, const Vec3& edge2, uint32_t material);

  // A curved surface sampled on a (columns + 1) x (rows + 1) lattice of
  // shared vertices, point(s, t) with s, t in [0, 1]; each lattice quad
  // becomes two triangles whose front is the side of
  // cross(d point/ds, d point/dt). With wrapS the last column reuses the
  // first (a closed lathe or cylinder: no seam of duplicate vertices).
  void addSurface(int columns, int rows, bool wrapS, const std::function<Vec3(float s, float t)>& point,
                  uint32_t material);

  uint32_t addVertex(const Vec3& p);
  void addTriangle(uint32_t a, uint32_t b, uint32_t c, uint32_t material);

  size_t triangleCount() const { return indices_.size() / 3; }
  // Moves the triangles into `cell` (positions, indices, materials), leaving
  // the builder empty.
  void moveInto(CellContent& cell);

 private:
  std::vector<float> positions_;
  std::vector<uint32_t> indices_;
  std::vector<uint32_t> materials_;
};

}  // namespace portico
