// `grid`: a uniform grid of voxels over the cell's triangles, traversed with
// a 3D-DDA (Amanatides & Woo 1987) and mailboxing. The paper's workhorse:
// it builds in O(n) and is hard to beat when triangles are spread evenly,
// as they are in most rooms.
//
// Layout: each voxel's triangles are copied, vertices and primitive id, into
// the voxel's own run of 4-wide packets (one copy per reference), so a voxel
// costs one row lookup and a contiguous read, and four triangles share one
// SIMD sign test before the scalar watertight test (grid_traversal.h). The
// row holds a coarse box around the voxel's contents, and each packet one
// around its four triangles (kept apart, a voxel's side by side): a voxel
// of a floor, a wall or a chair leg is mostly air, so most rays crossing an
// occupied voxel miss its box and load none of its packets, and in a voxel
// crowded with furniture most packets are skipped on their box. A run of
// voxels holding the same few triangles (along a floor, a wall, a ceiling)
// shares one packet.
//
// Parameters:
//   res=N      voxels along the longest axis of the bounds; the other axes get
//              as many as keep voxels near-cubic (at least 1). 1..512.
//              Default: chosen from the triangle count and the cell's shape.
//   density=L  for the automatic resolution: voxels per triangle (the lambda
//              of Cleary & Wyvill's rule), default 0.125. Swept on furnished
//              halls of 10k-500k triangles (`portico bench accel`): with the
//              content boxes culling the crowded voxels, 0.125 traces
//              as fast as 0.25-0.5 at 10k-100k and faster at 500k (fewer
//              voxels to cross), and builds faster with less memory
//              (references per triangle ~1.6 instead of ~1.9 at 0.5).
//
// Hits are identical, bit for bit, to those of `brute` for rays starting
// within a few grid diagonals of the cell (the renderer's rays start inside
// it or on its portals); see uniform_grid.cpp for why.
#pragma once

#include <array>
#include <cstdint>
#include <string_view>
#include <vector>

#include "common/accel/accelerator.h"
#include "common/accel/grid_traversal.h"

namespace portico {

struct UniformGridOptions {
  int resolution = 0;    // voxels along the longest axis; 0 = automatic
  double density = 0.125;  // automatic resolution: voxels per triangle
};

// Reads res and density from a `grid` spec.
UniformGridOptions readUniformGridOptions(AcceleratorParameters& parameters);

// Voxels per axis for a box of this extent holding triangleCount triangles:
// about density * triangleCount near-cubic voxels, 1..256 per axis. Axes too
// thin for one voxel get one, and the others share the voxel budget.
std::array<int, 3> automaticGridResolution(const std::array<double, 3>& extent,
                                           size_t triangleCount, double density);

// Voxels per axis for an explicit resolution: `longest` along the longest
// axis, the others in proportion to their extent (at least 1).
std::array<int, 3> resolutionFromLongestAxis(const std::array<double, 3>& extent, int longest);

class UniformGrid final : public Accelerator {
 public:
  // mesh's arrays must outlive this object.
  explicit UniformGrid(const MeshView& mesh, const UniformGridOptions& options = {},
                       std::string_view spec = "grid");

  Hit intersect(const Ray& ray) const override;
  bool occluded(const Ray& ray) const override;
  Bounds3 bounds() const override { return meshBounds_; }
  const AcceleratorStats& stats() const override { return stats_; }

  // Voxels per axis ({0, 0, 0} for an empty mesh).
  std::array<int, 3> resolution() const { return resolution_; }
  // The box the voxels tile: the bounds of the vertices' finite coordinates
  // (the mesh bounds, when every vertex is used and finite), slightly padded.
  std::array<double, 3> gridLow() const { return low_; }
  std::array<double, 3> voxelSize() const { return voxelSize_; }

 private:
  // The build's passes, and traversal's steps (uniform_grid.cpp).
  class Builder;
  struct VoxelWalk;
  struct ContentBoxes;

  template <bool AnyHit>
  bool traverse(const Ray& ray, Hit& best) const;

  MeshView mesh_;
  Bounds3 meshBounds_;
  // Geometry of the grid, in double: traversal computes its voxel boundaries
  // in double (and walks them in 64-bit fixed point) so that they are exact
  // to far below the triangle test's rounding.
  std::array<int, 3> resolution_{0, 0, 0};
  std::array<double, 3> low_{0, 0, 0}, high_{0, 0, 0};
  std::array<double, 3> voxelSize_{0, 0, 0}, inverseVoxelSize_{0, 0, 0};
  // The rows' content boxes: grown by contentMargin_, on a lattice of
  // latticeStep_ spacing that starts contentMargin_ below each voxel.
  double contentMargin_ = 0;
  std::array<double, 3> latticeStep_{0, 0, 0};
  // One bit per voxel (x fastest, then y, then z), set when it holds
  // references: small enough to stay in cache, so traversal crosses empty
  // voxels touching nothing else.
  std::vector<uint64_t> occupied_;
  // One row per voxel, indexed by the voxel (only the occupied voxels' rows
  // are written, and read): 16 bytes a voxel, ~2 bytes a triangle at the
  // default density, and no rank to count on the way to a row. The voxel's
  // triangles are the packets packets_[firstPacket .. endPacket), by increasing primitive
  // id, four to a packet, with their vertices (one copy per reference; a
  // voxel holding the one packet of the occupied voxel before it shares it).
  // low/high: the box its triangles' bounding boxes cover within the voxel,
  // on a lattice of 255 steps across the voxel grown by two reference
  // margins (rounded outwards), so a ray that misses it skips the voxel
  // without loading a packet (uniform_grid.cpp says why that is exact).
  struct VoxelRow {
    uint32_t firstPacket, endPacket;
    uint8_t low[4], high[4];  // x, y, z, and 0
  };
  std::vector<VoxelRow, grid_traversal::LargeArrayAllocator<VoxelRow>> rows_;
  std::vector<grid_traversal::TrianglePacket, grid_traversal::LargeArrayAllocator<grid_traversal::TrianglePacket>>
      packets_;
  // packetBoxes_[b]: the boxes of packets_[4b .. 4b + 3], each on its voxel's lattice.
  std::vector<grid_traversal::PacketBoxes4, grid_traversal::LargeArrayAllocator<grid_traversal::PacketBoxes4>>
      packetBoxes_;
  AcceleratorStats stats_;
};

}  // namespace portico
