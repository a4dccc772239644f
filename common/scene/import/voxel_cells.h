// Uniform-grid cells (Fradin & Meneveaux, §6.3): when a building's rooms are
// not known, its bounds are cut into RG x RG x RG voxels, each a cell, and
// the faces shared by neighbouring voxels are the portals.
//
//  * Cell ids: x + RG * (y + RG * z); names "voxel-x-y-z".
//  * Voxel faces are the same floats for both neighbours (one boundary table
//    per axis), so a portal lies exactly on both cells' faces.
//  * A triangle is written into every voxel it touches, by a conservative
//    separating-axis test (common/triangle_box_overlap.h) against the voxel grown by
//    overlapTolerance(): rounding may add a triangle to a neighbour, never
//    drop it. A triangle lying in a shared face goes to both voxels.
//  * Portals: for each axis, each of the RG - 1 inner planes, each of its
//    RG x RG faces: 3 RG^2 (RG - 1) rectangles, between voxel (.., k-1, ..)
//    and (.., k, ..).
//  * Lights: a light must emit from its own cell. One whose edges run along
//    the axes (every quad light of a box-like building) is cut at the voxel
//    faces into one AreaLight per voxel it covers (same radiance, so the
//    same total power); any other, and every triangle light, goes whole to
//    the voxel holding its centre, nudged to the emitting side (a ceiling
//    light on a voxel face belongs to the voxel below it).
//  * The camera's cell is the voxel holding its origin.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "common/math.h"
#include "common/scene/import/imported_scene.h"
#include "common/scene/store/scene_store.h"

namespace portico {

class VoxelGrid {
 public:
  // `bounds` must be finite and non-empty on every axis; resolution >= 1.
  VoxelGrid(const Bounds3& bounds, uint32_t resolution);

  uint32_t resolution() const { return resolution_; }
  uint32_t cellCount() const { return resolution_ * resolution_ * resolution_; }
  uint32_t cellId(uint32_t x, uint32_t y, uint32_t z) const { return x + resolution_ * (y + resolution_ * z); }
  std::array<uint32_t, 3> coordinates(uint32_t cell) const;
  static std::string cellName(const std::array<uint32_t, 3>& coordinates);
  Bounds3 cellBounds(uint32_t cell) const;
  // The k-th plane along `axis`, k in [0, resolution]: 0 and resolution are the grid's own faces.
  float boundary(int axis, uint32_t k) const { return boundaries_[axis][k]; }
  // The voxel slab along `axis` holding `value` (clamped to the grid; a value
  // on an inner plane belongs to the slab above it).
  uint32_t slab(int axis, float value) const;
  uint32_t locate(const Vec3& p) const;
  // First and last slab along `axis` whose closed extent touches [lo, hi].
  void touchedSlabs(int axis, float lo, float hi, uint32_t& first, uint32_t& last) const;
  // How much voxels grow for the conservative triangle test: 1e-5 of the
  // grid's largest extent, far above float rounding and far below geometry.
  float overlapTolerance() const { return tolerance_; }

 private:
  uint32_t resolution_;
  std::array<std::vector<float>, 3> boundaries_;
  float tolerance_;
};

// The AreaLights `light` becomes in `grid` (see the header comment), cell ids set.
std::vector<AreaLight> voxelLights(const ImportedLight& light, const VoxelGrid& grid);

// Writes `scene` into `writer` as the voxel cells of `grid` (bounds: the
// scene's padded bounds): portals, lights, camera, then the cells one at a
// time. The scene's own cells and portals are not used. Materials must
// already be added to `writer` in the scene's order.
void writeVoxelCells(const ImportedScene& scene, const VoxelGrid& grid, SceneStoreWriter& writer);

}  // namespace portico
