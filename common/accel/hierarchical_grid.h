// `hgrid`: a hierarchical uniform grid (the paper's §4.1). A top uniform
// grid as `grid` builds it; a voxel holding more than `max` triangle
// references gets its own uniform grid over the voxel's box, recursively,
// up to `depth` levels. Traversal is a 3D-DDA that, on reaching a voxel with
// a sub-grid, starts a new DDA over the sub-grid for the stretch of the ray
// inside that voxel, then resumes the outer one; mailboxing across levels.
//
// Choose it over `grid` when a cell mixes large empty spaces with dense
// clusters (a hall with a few finely tessellated pieces of furniture): the
// top grid stays coarse, and only the clusters pay for fine voxels.
//
// Parameters (spec "hgrid:res=16,max=64"):
//   res=N         voxels along the longest axis of the top grid (1..512).
//                 Default: automatic, as `grid` (Cleary & Wyvill, `density`).
//   max=M         a voxel with more than M references is subdivided
//                 (1..2^24). Default 32.
//   subres=N      voxels along the longest axis of every sub-grid (2..128).
//                 Default: automatic from the voxel's reference count and
//                 `subdensity`, like the top grid.
//   depth=L       levels of grids, the top one included (1..8). Default 3;
//                 depth=1 is a plain uniform grid.
//   density=D     automatic top resolution: voxels per triangle. Default 1,
//                 a third of `grid`'s: the top grid can stay coarse (empty
//                 space is crossed in few steps) since dense voxels refine.
//   subdensity=D  automatic sub-grid resolution: voxels per reference.
//                 Default 4.
// A voxel is subdivided only when its sub-grid has more than one voxel,
// sub-voxels are at least 8 reference margins wide (see the .cpp), and,
// below the top, it holds fewer references than the voxel it refines.
// Defaults from `portico bench accel` on furnished halls of 10k-1M
// triangles (docs/accelerator-benchmarks.md): deeper hierarchies or smaller
// `max` trace a little faster and build slower, with more memory.
//
// Hits are identical, bit for bit, to those of `brute` (and `grid`) for
// rays starting within a few diagonals of the cell: see
// hierarchical_grid.cpp. Statistics: nodes counts every voxel of every
// grid; depth is the grid level of a leaf voxel (top = 1).
#pragma once

#include <array>
#include <cstdint>
#include <string_view>
#include <vector>

#include "common/accel/accelerator.h"

namespace portico {

struct HierarchicalGridOptions {
  int resolution = 0;         // top grid, voxels along the longest axis; 0 = automatic
  int maxReferences = 32;     // a voxel holding more is subdivided
  int subResolution = 0;      // sub-grids, voxels along the longest axis; 0 = automatic
  int maxLevels = 3;          // levels of grids, the top one included
  double density = 1.0;       // automatic resolution of the top grid: voxels per triangle
  double subDensity = 4.0;    // automatic resolution of sub-grids: voxels per reference
};

// Reads res, max, subres, depth, density and subdensity from an `hgrid` spec.
HierarchicalGridOptions readHierarchicalGridOptions(AcceleratorParameters& parameters);

class HierarchicalGrid final : public Accelerator {
 public:
  // mesh's arrays must outlive this object.
  explicit HierarchicalGrid(const MeshView& mesh, const HierarchicalGridOptions& options = {},
                            std::string_view spec = "hgrid");

  Hit intersect(const Ray& ray) const override;
  bool occluded(const Ray& ray) const override;
  Bounds3 bounds() const override { return meshBounds_; }
  const AcceleratorStats& stats() const override { return stats_; }

  // One uniform grid of the hierarchy; grid 0 is the top one. Its voxels are
  // nodes_[firstNode ..) in x-fastest order. Geometry in double, like `grid`.
  struct GridRecord {
    std::array<double, 3> low{0, 0, 0};
    std::array<double, 3> voxelSize{0, 0, 0};
    std::array<double, 3> inverseVoxelSize{0, 0, 0};
    std::array<int, 3> resolution{0, 0, 0};
    uint32_t firstNode = 0;
    uint32_t level = 1;  // top = 1
  };
  // A voxel: a leaf (references_[first .. first + count)) or, when count is
  // kSubGrid, the sub-grid grids_[first].
  struct Node {
    uint32_t first = 0;
    uint32_t count = 0;
    bool isSubGrid() const { return count == kSubGrid; }
  };
  static constexpr uint32_t kSubGrid = 0xffffffffu;

  // The flat hierarchy (for tests and statistics).
  const std::vector<GridRecord>& grids() const { return grids_; }
  const std::vector<Node>& nodes() const { return nodes_; }

 private:
  struct Builder;
  template <bool AnyHit>
  bool traverse(const Ray& ray, Hit& best) const;

  MeshView mesh_;
  Bounds3 meshBounds_;
  std::vector<GridRecord> grids_;
  std::vector<Node> nodes_;
  std::vector<uint32_t> references_;
  // One bit per node, set when it is not an empty leaf: traversal crosses
  // empty voxels without touching nodes_.
  std::vector<uint64_t> occupied_;
  AcceleratorStats stats_;
};

}  // namespace portico
