// Uniform grid: build (two passes over the triangles, count then fill, into
// compressed rows) and traversal (3D-DDA with mailboxing).
//
// Why the grid returns exactly brute force's hit. Traversal keeps the best
// hit over every triangle tested so far (by closerThan) and stops after the
// first voxel whose exit distance is >= that hit's t. This is exact if every
// triangle X whose computed hit tX is <= the final t is referenced in some
// voxel visited by then. The point P = origin + tX * direction lies in a
// visited voxel (the DDA runs in double, so its voxel boundaries are exact
// far below float rounding), and P lies within the triangle test's rounding
// error of X (the watertight test is backward stable: its t is exact for
// vertices moved by a few float ulps of their distance to the ray origin).
// So each triangle is referenced in every voxel within a margin of its
// bounding box (and of the triangle itself, when the overlap test refines
// it), the margin being 1e-5 of the grid's size: well above that error for
// ray origins up to several grid diagonals away.
//
// Ties (equal t, smaller primitive wins) follow from the same argument: two
// triangles hit at the same t share P, so both are referenced where P is.
#include "common/accel/uniform_grid.h"

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

namespace portico {

namespace {

constexpr int kMaxAutomaticResolution = 256;
constexpr int kMaxExplicitResolution = 512;
// Triangles are referenced in every voxel within this fraction of the grid's
// longest side (see the top of the file).
constexpr double kReferenceMargin = 1e-5;
// The grid box is the mesh bounds grown by this fraction of its longest side,
// so that no triangle (with its margin) touches the grid's faces.
constexpr double kGridPadding = 1e-4;


}  // namespace

std::array<int, 3> automaticGridResolution(const std::array<double, 3>& extent,
                                           size_t triangleCount, double density) {
  // Cleary & Wyvill: voxels of side s = cbrt(volume / (density * n)), so
  // resolution_axis = extent_axis / s. An axis thinner than one voxel gets a
  // single voxel, and the rule is re-applied in the remaining dimensions
  // (a flat floor gets a 2D grid of about density * n voxels).
  const double targetVoxels = std::max(1.0, density * double(triangleCount));
  std::array<int, 3> resolution{1, 1, 1};
  bool active[3] = {extent[0] > 0, extent[1] > 0, extent[2] > 0};
  for (int round = 0; round < 3; ++round) {
    double product = 1.0;
    int dimensions = 0;
    for (int axis = 0; axis < 3; ++axis)
      if (active[axis]) product *= extent[axis], ++dimensions;
    if (dimensions == 0) break;
    const double voxelsPerUnit = std::pow(targetVoxels / product, 1.0 / dimensions);
    bool dropped = false;
    for (int axis = 0; axis < 3; ++axis)
      if (active[axis] && extent[axis] * voxelsPerUnit < 1.0) active[axis] = false, dropped = true;
    if (dropped) continue;
    for (int axis = 0; axis < 3; ++axis) {
      if (!active[axis]) continue;
      const double voxels = std::round(extent[axis] * voxelsPerUnit);
      resolution[axis] =
          static_cast<int>(std::clamp(voxels, 1.0, double(kMaxAutomaticResolution)));
    }
    break;
  }
  return resolution;
}

std::array<int, 3> resolutionFromLongestAxis(const std::array<double, 3>& extent, int longest) {
  const double longestExtent = std::max({extent[0], extent[1], extent[2]});
  std::array<int, 3> resolution{};
  for (int axis = 0; axis < 3; ++axis) {
    const double voxels = std::round(longest * (extent[axis] / longestExtent));
    resolution[axis] = static_cast<int>(std::clamp(voxels, 1.0, double(longest)));
  }
  return resolution;
}

UniformGridOptions readUniformGridOptions(AcceleratorParameters& parameters) {
  UniformGridOptions options;
  options.resolution = parameters.integer("res", 0, 1, kMaxExplicitResolution);
  options.density = parameters.positiveNumber("density", options.density);
  return options;
}

// ---------------------------------------------------------------------------
// Build

UniformGrid::UniformGrid(const MeshView& mesh, const UniformGridOptions& options,
                         std::string_view spec)
    : mesh_(mesh) {
  const auto start = std::chrono::steady_clock::now();
  if (mesh.triangleCount >= kNoPrimitive)
    throw std::invalid_argument("grid: " + std::to_string(mesh.triangleCount) +
                                " triangles exceed the 32-bit primitive ids; split the cell");
  const uint32_t triangleCount = static_cast<uint32_t>(mesh.triangleCount);

  // Bounds over the triangles that can be placed. Triangles with a
  // non-finite vertex cannot be, and are left out (such input should be
  // refused at import).
  for (uint32_t primitive = 0; primitive < triangleCount; ++primitive) {
    const Bounds3 box = mesh.triangleBounds(primitive);
    if (isFinite(box.lo) && isFinite(box.hi)) meshBounds_.extend(box);
  }

  stats_.spec = std::string(spec);
  if (meshBounds_.empty()) {
    voxelStart_.assign(1, 0);
    stats_.bytes = sizeof(*this) + sizeof(uint32_t);
    stats_.buildMs =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return;
  }

  // Grid box: the bounds padded on every axis, so flat bounds get a
  // thickness and no triangle touches a face of the grid.
  const Vec3 extent = meshBounds_.diagonal();
  double scale = maxComponent(extent);
  if (scale == 0.0) {
    // Every vertex is the same point: any small box will do.
    const Vec3 magnitude = max(-meshBounds_.lo, meshBounds_.hi);
    scale = std::max(1e-6 * maxComponent(magnitude), 1e-30);
  }
  const double padding = kGridPadding * scale;
  for (int axis = 0; axis < 3; ++axis) {
    low_[axis] = double(meshBounds_.lo[axis]) - padding;
    high_[axis] = double(meshBounds_.hi[axis]) + padding;
  }
  const std::array<double, 3> gridExtent{high_[0] - low_[0], high_[1] - low_[1],
                                         high_[2] - low_[2]};
  resolution_ = options.resolution > 0
                    ? resolutionFromLongestAxis(gridExtent, options.resolution)
                    : automaticGridResolution(gridExtent, triangleCount, options.density);
  for (int axis = 0; axis < 3; ++axis) {
    voxelSize_[axis] = gridExtent[axis] / resolution_[axis];
    inverseVoxelSize_[axis] = resolution_[axis] / gridExtent[axis];
  }
  const double margin = kReferenceMargin * std::max({gridExtent[0], gridExtent[1], gridExtent[2]});
  const Double3 voxelHalfSize{0.5 * voxelSize_[0] + margin, 0.5 * voxelSize_[1] + margin,
                              0.5 * voxelSize_[2] + margin};

  const auto voxelIndex = [&](int axis, double coordinate) {
    const double index = std::floor((coordinate - low_[axis]) * inverseVoxelSize_[axis]);
    return static_cast<int>(std::clamp(index, 0.0, double(resolution_[axis] - 1)));
  };
  const uint64_t voxelCount = uint64_t(resolution_[0]) * resolution_[1] * resolution_[2];
  const uint32_t strideY = uint32_t(resolution_[0]);
  const uint32_t strideZ = uint32_t(resolution_[0]) * uint32_t(resolution_[1]);

  // Calls visit(voxel) for every voxel the triangle (grown by the margin)
  // overlaps. The same function drives both passes, so they agree.
  const auto forEachVoxelOf = [&](uint32_t primitive, auto&& visit) {
    Vec3 v0, v1, v2;
    mesh.triangle(primitive, v0, v1, v2);
    const Bounds3 box = mesh.triangleBounds(primitive);
    if (!isFinite(box.lo) || !isFinite(box.hi)) return;
    int first[3], last[3], spannedAxes = 0;
    for (int axis = 0; axis < 3; ++axis) {
      first[axis] = voxelIndex(axis, double(box.lo[axis]) - margin);
      last[axis] = voxelIndex(axis, double(box.hi[axis]) + margin);
      spannedAxes += last[axis] > first[axis];
    }
    // A box one voxel thick on two axes is a row of voxels, and a connected
    // triangle spanning the row overlaps all of them: no overlap test needed.
    const bool refine = spannedAxes >= 2;
    const Double3 a = toDouble(v0), b = toDouble(v1), c = toDouble(v2);
    for (int z = first[2]; z <= last[2]; ++z)
      for (int y = first[1]; y <= last[1]; ++y)
        for (int x = first[0]; x <= last[0]; ++x) {
          if (refine) {
            const Double3 center{low_[0] + (x + 0.5) * voxelSize_[0],
                                 low_[1] + (y + 0.5) * voxelSize_[1],
                                 low_[2] + (z + 0.5) * voxelSize_[2]};
            if (!triangleOverlapsBoxBeyondBounds(center, voxelHalfSize, a, b, c)) continue;
          }
          visit(uint32_t(x) + strideY * uint32_t(y) + strideZ * uint32_t(z));
        }
  };

  // Pass 1: count the references of each voxel, then turn the counts into
  // each voxel's end offset (inclusive prefix sum).
  voxelStart_.assign(voxelCount + 1, 0);
  for (uint32_t primitive = 0; primitive < triangleCount; ++primitive)
    forEachVoxelOf(primitive, [&](uint32_t voxel) { ++voxelStart_[voxel]; });
  uint64_t total = 0;
  occupied_.assign((voxelCount + 63) / 64, 0);
  for (uint64_t voxel = 0; voxel < voxelCount; ++voxel) {
    if (voxelStart_[voxel] > 0) {
      ++stats_.leaves;
      occupied_[voxel / 64] |= uint64_t(1) << (voxel % 64);
    }
    total += voxelStart_[voxel];
    if (total > std::numeric_limits<uint32_t>::max())
      throw std::invalid_argument("grid: more than 2^32 triangle references; use a lower res");
    voxelStart_[voxel] = static_cast<uint32_t>(total);
  }
  voxelStart_[voxelCount] = static_cast<uint32_t>(total);

  // Pass 2: fill from each voxel's end backwards. Going through the
  // primitives in decreasing order leaves each voxel's list increasing, and
  // leaves voxelStart_[i] at voxel i's first reference.
  references_.resize(total);
  for (uint32_t primitive = triangleCount; primitive-- > 0;)
    forEachVoxelOf(primitive, [&](uint32_t voxel) { references_[--voxelStart_[voxel]] = primitive; });

  stats_.nodes = voxelCount;
  stats_.emptyLeaves = voxelCount - stats_.leaves;
  stats_.triangleReferences = total;
  stats_.averageDepth = 1;
  stats_.maxDepth = 1;
  stats_.bytes = sizeof(*this) + voxelStart_.capacity() * sizeof(uint32_t) +
                 references_.capacity() * sizeof(uint32_t) + occupied_.capacity() * sizeof(uint64_t);
  stats_.buildMs =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

// ---------------------------------------------------------------------------
// Traversal

template <bool AnyHit>
bool UniformGrid::traverse(const Ray& ray, Hit& best) const {
  if (references_.empty() || !hasFiniteOriginAndDirection(ray)) return false;
  const double origin[3] = {ray.origin.x, ray.origin.y, ray.origin.z};
  const double direction[3] = {ray.direction.x, ray.direction.y, ray.direction.z};
  if (direction[0] == 0.0 && direction[1] == 0.0 && direction[2] == 0.0) return false;

  // Clip [tMin, tMax] to the grid box.
  double tEnter = ray.tMin, tExit = ray.tMax;
  if (!grid_traversal::clipToBox(origin, direction, low_.data(), high_.data(), tEnter, tExit)) return false;

  // DDA set-up: the voxel at the entry point, and per axis the distance to
  // the next voxel boundary (tNext) and between boundaries (tDelta).
  int voxel[3], step[3], outside[3];
  double tNext[3], tDelta[3];
  for (int axis = 0; axis < 3; ++axis) {
    const double entry = origin[axis] + tEnter * direction[axis];
    const double index = std::floor((entry - low_[axis]) * inverseVoxelSize_[axis]);
    voxel[axis] = static_cast<int>(std::clamp(index, 0.0, double(resolution_[axis] - 1)));
    if (direction[axis] > 0.0) {
      step[axis] = 1;
      outside[axis] = resolution_[axis];
      tNext[axis] = (low_[axis] + (voxel[axis] + 1) * voxelSize_[axis] - origin[axis]) / direction[axis];
      tDelta[axis] = voxelSize_[axis] / direction[axis];
    } else if (direction[axis] < 0.0) {
      step[axis] = -1;
      outside[axis] = -1;
      tNext[axis] = (low_[axis] + voxel[axis] * voxelSize_[axis] - origin[axis]) / direction[axis];
      tDelta[axis] = -voxelSize_[axis] / direction[axis];
    } else {
      step[axis] = 0;
      outside[axis] = -2;  // never reached
      tNext[axis] = std::numeric_limits<double>::infinity();
      tDelta[axis] = 0.0;
    }
  }

  const WatertightRay frame(ray.direction);
  grid_traversal::Mailbox mailbox;
  const uint32_t strideY = uint32_t(resolution_[0]);
  const uint32_t strideZ = uint32_t(resolution_[0]) * uint32_t(resolution_[1]);
  const uint32_t* const references = references_.data();

  for (;;) {
    const uint32_t index = uint32_t(voxel[0]) + strideY * uint32_t(voxel[1]) + strideZ * uint32_t(voxel[2]);
    const double tVoxelExit = std::min({tNext[0], tNext[1], tNext[2]});
    const bool occupied = (occupied_[index / 64] >> (index % 64)) & 1;
    if (occupied && grid_traversal::testReferences<AnyHit>(references, voxelStart_[index], voxelStart_[index + 1],
                                                            mailbox, mesh_, frame, ray, best))
      return true;
    // Nothing in a later voxel can be nearer than a hit within this one.
    // (Hits beyond it are kept, not re-tested: the mailbox would skip them.)
    if constexpr (!AnyHit) {
      if (best.found() && double(best.t) <= tVoxelExit) return true;
    }
    if (tVoxelExit >= tExit) break;
    const int axis = tNext[0] <= tNext[1] ? (tNext[0] <= tNext[2] ? 0 : 2)
                                          : (tNext[1] <= tNext[2] ? 1 : 2);
    voxel[axis] += step[axis];
    if (voxel[axis] == outside[axis]) break;
    tNext[axis] += tDelta[axis];
  }
  return best.found();
}

Hit UniformGrid::intersect(const Ray& ray) const {
  Hit best;
  traverse<false>(ray, best);
  return best;
}

bool UniformGrid::occluded(const Ray& ray) const {
  Hit unused;
  return traverse<true>(ray, unused);
}

}  // namespace portico
