// Hierarchical grid: build (per grid, two passes over its triangles, count
// then fill; voxels over the limit recurse into a sub-grid) and traversal
// (nested 3D-DDAs with one explicit stack, mailboxing across levels).
//
// Why the hierarchical grid returns exactly brute force's hit: the argument
// of uniform_grid.cpp, unchanged. Traversal keeps the best hit over every
// triangle tested so far (by closerThan) and stops after the first leaf
// voxel whose exit distance is >= that hit's t. The leaf voxels visited, in
// order, cover the ray's parameter range without gaps: each DDA covers
// exactly the stretch [enter, exit) its parent's voxel gave it, in double
// precision. A triangle X whose computed hit tX is <= the final t therefore
// has its hit point P within double rounding of a visited leaf voxel, and P
// lies within the triangle test's rounding error of X. Every triangle is
// referenced in every leaf voxel within an absolute margin of 1e-5 of the
// top grid's size (the same margin at every level), far above both errors
// for ray origins up to several cell diagonals away: X was tested.
//
// Ties (equal t, smaller primitive wins) follow from the same argument: two
// triangles hit at the same t share P, so both are referenced where P is.
#include "common/accel/hierarchical_grid.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>

#include "common/accel/grid_traversal.h"
#include "common/accel/triangle_intersect.h"
#include "common/triangle_box_overlap.h"
#include "common/accel/uniform_grid.h"

namespace portico {

namespace {

constexpr int kMaxExplicitResolution = 512;
constexpr int kMaxSubResolution = 128;
// Levels of grids, the top one included; also the traversal stack's size.
constexpr int kMaxLevels = 8;
// Triangles are referenced in every voxel within this fraction of the top
// grid's longest side (see the top of the file).
constexpr double kReferenceMargin = 1e-5;
// The top grid box is the mesh bounds grown by this fraction of its longest
// side, so that no triangle (with its margin) touches the grid's faces.
constexpr double kGridPadding = 1e-4;
// A triangle whose grown bounding box spans at most this many voxels is
// referenced in all of them, without the triangle-box overlap test (as in
// uniform_grid.cpp).
constexpr uint64_t kBoxOnlyVoxels = 8;
// No sub-grid has voxels narrower than this many reference margins.
constexpr double kMinimumVoxelInMargins = 8;

uint64_t voxelCountOf(const std::array<int, 3>& resolution) {
  return uint64_t(resolution[0]) * uint64_t(resolution[1]) * uint64_t(resolution[2]);
}

double millisecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

HierarchicalGridOptions readHierarchicalGridOptions(AcceleratorParameters& parameters) {
  HierarchicalGridOptions options;
  options.resolution = parameters.integer("res", 0, 1, kMaxExplicitResolution);
  options.maxReferences = parameters.integer("max", options.maxReferences, 1, 1 << 24);
  options.subResolution = parameters.integer("subres", 0, 2, kMaxSubResolution);
  options.maxLevels = parameters.integer("depth", options.maxLevels, 1, kMaxLevels);
  options.density = parameters.positiveNumber("density", options.density);
  options.subDensity = parameters.positiveNumber("subdensity", options.subDensity);
  return options;
}

// ---------------------------------------------------------------------------
// Build

// Fills one grid record's nodes from its triangles, and recurses into the
// voxels that get sub-grids. Grids are laid out depth first: a sub-grid's
// nodes follow its parent's, and its own sub-grids follow it.
struct HierarchicalGrid::Builder {
  const MeshView& mesh;
  const HierarchicalGridOptions& options;
  HierarchicalGrid& grid;
  double margin = 0;
  uint64_t leafDepthSum = 0;

  // Calls visit(voxel) for every voxel of `record` that the triangle (grown
  // by the margin) overlaps. The same function drives both passes, so they agree.
  template <typename Visit>
  void forEachVoxelOf(const GridRecord& record, const Double3& halfSize, uint32_t primitive,
                      Visit&& visit) const {
    Vec3 v0, v1, v2;
    mesh.triangle(primitive, v0, v1, v2);
    const Bounds3 box = mesh.triangleBounds(primitive);
    if (!isFinite(box.lo) || !isFinite(box.hi)) return;
    const auto voxelIndex = [&](int axis, double coordinate) {
      const double index = std::floor((coordinate - record.low[axis]) * record.inverseVoxelSize[axis]);
      return static_cast<int>(std::clamp(index, 0.0, double(record.resolution[axis] - 1)));
    };
    int first[3], last[3], spannedAxes = 0;
    for (int axis = 0; axis < 3; ++axis) {
      first[axis] = voxelIndex(axis, double(box.lo[axis]) - margin);
      last[axis] = voxelIndex(axis, double(box.hi[axis]) + margin);
      spannedAxes += last[axis] > first[axis];
    }
    // A box one voxel thick on two axes is a row of voxels, and a connected
    // triangle spanning the row overlaps all of them: no overlap test needed.
    // Nor for a box of a few voxels: referencing the triangle in all of them
    // costs a few tests at most, never exactness (as `grid` does).
    const uint64_t boxVoxels =
        uint64_t(last[0] - first[0] + 1) * uint64_t(last[1] - first[1] + 1) * uint64_t(last[2] - first[2] + 1);
    const bool refine = spannedAxes >= 2 && boxVoxels > kBoxOnlyVoxels;
    const grid_traversal::TriangleVoxelOverlap overlap =
        refine ? grid_traversal::TriangleVoxelOverlap(v0, v1, v2, halfSize) : grid_traversal::TriangleVoxelOverlap();
    const uint32_t strideY = uint32_t(record.resolution[0]);
    const uint32_t strideZ = strideY * uint32_t(record.resolution[1]);
    for (int z = first[2]; z <= last[2]; ++z)
      for (int y = first[1]; y <= last[1]; ++y)
        for (int x = first[0]; x <= last[0]; ++x) {
          if (refine && !overlap.overlaps(record.low[0] + (x + 0.5) * record.voxelSize[0],
                                          record.low[1] + (y + 0.5) * record.voxelSize[1],
                                          record.low[2] + (z + 0.5) * record.voxelSize[2]))
            continue;
          visit(uint32_t(x) + strideY * uint32_t(y) + strideZ * uint32_t(z));
        }
  }

  // Appends a grid record over `low` + `extent`, with its nodes; returns its index.
  uint32_t addGrid(const std::array<double, 3>& low, const std::array<double, 3>& extent,
                   const std::array<int, 3>& resolution, uint32_t level) {
    GridRecord record;
    record.low = low;
    record.resolution = resolution;
    for (int axis = 0; axis < 3; ++axis) {
      record.voxelSize[axis] = extent[axis] / resolution[axis];
      record.inverseVoxelSize[axis] = resolution[axis] / extent[axis];
    }
    const uint64_t firstNode = grid.nodes_.size();
    const uint64_t voxels = voxelCountOf(resolution);
    if (firstNode + voxels >= std::numeric_limits<uint32_t>::max())
      throw std::invalid_argument("hgrid: more than 2^32 voxels; use a lower res, subres or depth");
    if (grid.grids_.size() >= std::numeric_limits<uint32_t>::max())
      throw std::invalid_argument("hgrid: more than 2^32 sub-grids; use a higher max");
    record.firstNode = uint32_t(firstNode);
    record.level = level;
    grid.nodes_.resize(firstNode + voxels);
    grid.grids_.push_back(record);
    return uint32_t(grid.grids_.size() - 1);
  }

  // triangles: increasing primitive ids. parentCount: the references of the
  // voxel this grid refines (0 for the top grid).
  void fill(uint32_t gridIndex, const uint32_t* triangles, size_t triangleCount, size_t parentCount) {
    // A copy: grids_ grows during the recursion below.
    const GridRecord record = grid.grids_[gridIndex];
    const uint64_t voxelCount = voxelCountOf(record.resolution);
    const Double3 halfSize{0.5 * record.voxelSize[0] + margin, 0.5 * record.voxelSize[1] + margin,
                           0.5 * record.voxelSize[2] + margin};

    // Pass 1: count the references of each voxel, then turn the counts into
    // each voxel's end offset (inclusive prefix sum).
    std::vector<uint64_t> voxelStart(voxelCount + 1, 0);
    for (size_t i = 0; i < triangleCount; ++i)
      forEachVoxelOf(record, halfSize, triangles[i], [&](uint32_t voxel) { ++voxelStart[voxel]; });
    uint64_t total = 0;
    for (uint64_t voxel = 0; voxel < voxelCount; ++voxel) {
      total += voxelStart[voxel];
      voxelStart[voxel] = total;
    }
    voxelStart[voxelCount] = total;

    // Pass 2: fill from each voxel's end backwards. Going through the
    // triangles in decreasing order leaves each voxel's list increasing.
    std::vector<uint32_t> references(total);
    for (size_t i = triangleCount; i-- > 0;) {
      const uint32_t primitive = triangles[i];
      forEachVoxelOf(record, halfSize, primitive,
                     [&](uint32_t voxel) { references[--voxelStart[voxel]] = primitive; });
    }

    // Leaves, empty voxels and sub-grids.
    for (uint64_t voxel = 0; voxel < voxelCount; ++voxel) {
      const uint64_t begin = voxelStart[voxel], count = voxelStart[voxel + 1] - begin;
      const size_t nodeIndex = record.firstNode + voxel;
      if (count == 0) {
        ++grid.stats_.emptyLeaves;
        continue;  // nodes_ entries start as empty leaves
      }
      // Subdivide while it pays: over the limit, levels left, and fewer
      // references than the voxel being refined (a sub-voxel that every
      // triangle of its parent overlaps gains nothing from more levels).
      const bool progress = parentCount == 0 || count < parentCount;
      if (count > uint64_t(options.maxReferences) && int(record.level) < options.maxLevels && progress) {
        const int x = int(voxel % uint64_t(record.resolution[0]));
        const int y = int(voxel / uint64_t(record.resolution[0]) % uint64_t(record.resolution[1]));
        const int z = int(voxel / (uint64_t(record.resolution[0]) * uint64_t(record.resolution[1])));
        const std::array<double, 3> low{record.low[0] + x * record.voxelSize[0],
                                        record.low[1] + y * record.voxelSize[1],
                                        record.low[2] + z * record.voxelSize[2]};
        const std::array<double, 3>& extent = record.voxelSize;
        std::array<int, 3> resolution =
            options.subResolution > 0 ? resolutionFromLongestAxis(extent, options.subResolution)
                                      : automaticGridResolution(extent, count, options.subDensity);
        // Sub-voxels much smaller than the reference margin would all hold
        // the same triangles: keep them at least kMinimumVoxelInMargins wide.
        for (int axis = 0; axis < 3; ++axis)
          resolution[axis] = int(std::clamp(std::floor(extent[axis] / (kMinimumVoxelInMargins * margin)), 1.0,
                                            double(resolution[axis])));
        if (voxelCountOf(resolution) > 1) {
          const uint32_t child = addGrid(low, extent, resolution, record.level + 1);
          grid.nodes_[nodeIndex] = Node{child, kSubGrid};
          fill(child, references.data() + begin, count, count);
          continue;
        }
      }
      if (grid.references_.size() + count > std::numeric_limits<uint32_t>::max())
        throw std::invalid_argument("hgrid: more than 2^32 triangle references; use a lower res or density");
      grid.nodes_[nodeIndex] = Node{uint32_t(grid.references_.size()), uint32_t(count)};
      grid.references_.insert(grid.references_.end(), references.begin() + begin,
                              references.begin() + begin + count);
      ++grid.stats_.leaves;
      leafDepthSum += record.level;
      grid.stats_.maxDepth = std::max(grid.stats_.maxDepth, record.level);
    }
  }
};

HierarchicalGrid::HierarchicalGrid(const MeshView& mesh, const HierarchicalGridOptions& options,
                                   std::string_view spec)
    : mesh_(mesh) {
  const auto start = std::chrono::steady_clock::now();
  stats_.spec = std::string(spec);
  if (mesh.triangleCount >= kNoPrimitive)
    throw std::invalid_argument("hgrid: " + std::to_string(mesh.triangleCount) +
                                " triangles exceed the 32-bit primitive ids; split the cell");
  const uint32_t triangleCount = static_cast<uint32_t>(mesh.triangleCount);

  // Bounds over the triangles that can be placed (finite vertices), as `grid`.
  std::vector<uint32_t> placeable;
  placeable.reserve(triangleCount);
  for (uint32_t primitive = 0; primitive < triangleCount; ++primitive) {
    const Bounds3 box = mesh.triangleBounds(primitive);
    if (isFinite(box.lo) && isFinite(box.hi)) {
      meshBounds_.extend(box);
      placeable.push_back(primitive);
    }
  }
  if (meshBounds_.empty()) {
    stats_.bytes = sizeof(*this);
    stats_.buildMs = millisecondsSince(start);
    return;
  }

  // Top grid box: the bounds padded on every axis (see uniform_grid.cpp).
  const Vec3 extent = meshBounds_.diagonal();
  double scale = maxComponent(extent);
  if (scale == 0.0) {
    const Vec3 magnitude = max(-meshBounds_.lo, meshBounds_.hi);
    scale = std::max(1e-6 * maxComponent(magnitude), 1e-30);
  }
  const double padding = kGridPadding * scale;
  std::array<double, 3> low{}, gridExtent{};
  for (int axis = 0; axis < 3; ++axis) {
    low[axis] = double(meshBounds_.lo[axis]) - padding;
    gridExtent[axis] = (double(meshBounds_.hi[axis]) + padding) - low[axis];
  }
  const std::array<int, 3> resolution =
      options.resolution > 0 ? resolutionFromLongestAxis(gridExtent, options.resolution)
                             : automaticGridResolution(gridExtent, placeable.size(), options.density);

  Builder builder{mesh, options, *this};
  builder.margin = kReferenceMargin * std::max({gridExtent[0], gridExtent[1], gridExtent[2]});
  builder.addGrid(low, gridExtent, resolution, 1);
  builder.fill(0, placeable.data(), placeable.size(), 0);

  occupied_.assign((nodes_.size() + 63) / 64, 0);
  for (size_t node = 0; node < nodes_.size(); ++node)
    if (nodes_[node].count != 0) occupied_[node / 64] |= uint64_t(1) << (node % 64);

  stats_.nodes = nodes_.size();
  stats_.triangleReferences = references_.size();
  stats_.averageDepth = stats_.leaves > 0 ? double(builder.leafDepthSum) / double(stats_.leaves) : 0.0;
  stats_.bytes = sizeof(*this) + grids_.capacity() * sizeof(GridRecord) + nodes_.capacity() * sizeof(Node) +
                 references_.capacity() * sizeof(uint32_t) + occupied_.capacity() * sizeof(uint64_t);
  stats_.buildMs = millisecondsSince(start);
}

// ---------------------------------------------------------------------------
// Traversal

namespace {

// One level's 3D-DDA (Amanatides & Woo) over the stretch [tVoxelEnter of its
// first voxel, tExit] of the ray.
struct DdaState {
  int voxel[3];
  int step[3];
  int outside[3];
  double tNext[3];
  double tDelta[3];
  double tVoxelEnter;  // where the ray enters the current voxel
  double tExit;        // end of the stretch this DDA covers
  uint32_t firstNode;
  uint32_t strideY, strideZ;

  void start(const HierarchicalGrid::GridRecord& grid, const double origin[3], const double direction[3],
             const double inverseDirection[3], double tEnter, double tEnd) {
    tVoxelEnter = tEnter;
    tExit = tEnd;
    firstNode = grid.firstNode;
    strideY = uint32_t(grid.resolution[0]);
    strideZ = strideY * uint32_t(grid.resolution[1]);
    for (int axis = 0; axis < 3; ++axis) {
      const double entry = origin[axis] + tEnter * direction[axis];
      const double index = std::floor((entry - grid.low[axis]) * grid.inverseVoxelSize[axis]);
      voxel[axis] = static_cast<int>(std::clamp(index, 0.0, double(grid.resolution[axis] - 1)));
      if (direction[axis] > 0.0) {
        step[axis] = 1;
        outside[axis] = grid.resolution[axis];
        tNext[axis] =
            (grid.low[axis] + (voxel[axis] + 1) * grid.voxelSize[axis] - origin[axis]) * inverseDirection[axis];
        tDelta[axis] = grid.voxelSize[axis] * inverseDirection[axis];
      } else if (direction[axis] < 0.0) {
        step[axis] = -1;
        outside[axis] = -1;
        tNext[axis] = (grid.low[axis] + voxel[axis] * grid.voxelSize[axis] - origin[axis]) * inverseDirection[axis];
        tDelta[axis] = -grid.voxelSize[axis] * inverseDirection[axis];
      } else {
        step[axis] = 0;
        outside[axis] = -2;  // never reached
        tNext[axis] = std::numeric_limits<double>::infinity();
        tDelta[axis] = 0.0;
      }
    }
  }
  uint32_t node() const {
    return firstNode + uint32_t(voxel[0]) + strideY * uint32_t(voxel[1]) + strideZ * uint32_t(voxel[2]);
  }
  double voxelExit() const { return std::min({tNext[0], tNext[1], tNext[2], tExit}); }
  // Moves to the next voxel along the ray; false when the stretch is done.
  bool advance() {
    const int axis = tNext[0] <= tNext[1] ? (tNext[0] <= tNext[2] ? 0 : 2) : (tNext[1] <= tNext[2] ? 1 : 2);
    if (tNext[axis] >= tExit) return false;
    voxel[axis] += step[axis];
    if (voxel[axis] == outside[axis]) return false;
    tVoxelEnter = tNext[axis];
    tNext[axis] += tDelta[axis];
    return true;
  }
};

}  // namespace

template <bool AnyHit>
bool HierarchicalGrid::traverse(const Ray& ray, Hit& best) const {
  if (references_.empty() || !hasFiniteOriginAndDirection(ray)) return false;
  const double origin[3] = {ray.origin.x, ray.origin.y, ray.origin.z};
  const double direction[3] = {ray.direction.x, ray.direction.y, ray.direction.z};
  if (direction[0] == 0.0 && direction[1] == 0.0 && direction[2] == 0.0) return false;
  const double inverseDirection[3] = {direction[0] != 0.0 ? 1.0 / direction[0] : 0.0,
                                      direction[1] != 0.0 ? 1.0 / direction[1] : 0.0,
                                      direction[2] != 0.0 ? 1.0 / direction[2] : 0.0};

  // Clip [tMin, tMax] to the top grid box, as `grid` does.
  const GridRecord& top = grids_[0];
  double low[3], high[3];
  for (int axis = 0; axis < 3; ++axis)
    low[axis] = top.low[axis], high[axis] = top.low[axis] + top.resolution[axis] * top.voxelSize[axis];
  double tEnter = ray.tMin, tExit = ray.tMax;
  if (!grid_traversal::clipToBox(origin, direction, low, high, tEnter, tExit)) return false;

  DdaState stack[kMaxLevels];
  int level = 0;
  stack[0].start(top, origin, direction, inverseDirection, tEnter, tExit);

  const WatertightRay frame(ray.direction);
  grid_traversal::Mailbox<64> mailbox;
  const uint32_t* const references = references_.data();
  const Node* const nodes = nodes_.data();
  const uint64_t* const occupied = occupied_.data();

  for (;;) {
    DdaState& dda = stack[level];
    const uint32_t index = dda.node();
    const double tVoxelExit = dda.voxelExit();
    if ((occupied[index / 64] >> (index % 64)) & 1) {
      const Node node = nodes[index];
      if (node.isSubGrid()) {
        // Re-initialise a DDA for the sub-grid over this voxel's stretch of
        // the ray; the outer DDA resumes when it is done.
        stack[level + 1].start(grids_[node.first], origin, direction, inverseDirection, dda.tVoxelEnter,
                               tVoxelExit);
        ++level;
        continue;
      }
      if (grid_traversal::testReferences<AnyHit>(references, node.first, node.first + node.count, mailbox, mesh_,
                                                 frame, ray, best))
        return true;
    }
    // Nothing in a later voxel can be nearer than a hit within this one.
    if constexpr (!AnyHit) {
      if (best.found() && double(best.t) <= tVoxelExit) return true;
    }
    // Next voxel: in this grid, or, when its stretch is done, in the
    // enclosing ones.
    while (!stack[level].advance()) {
      if (level == 0) return best.found();
      --level;
    }
  }
}

Hit HierarchicalGrid::intersect(const Ray& ray) const {
  Hit best;
  traverse<false>(ray, best);
  return best;
}

bool HierarchicalGrid::occluded(const Ray& ray) const {
  Hit unused;
  return traverse<true>(ray, unused);
}

}  // namespace portico
