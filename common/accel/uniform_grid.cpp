// Uniform grid: build (the grid's box from one sequential read of the
// vertices, one pass over the triangles listing their voxels and counting
// them per voxel, a counting sort of the triangles by voxel, then one
// sequential pass that copies each voxel's triangles' vertices into its run
// of 4-wide packets and rounds their boxes onto the voxel's lattice) and
// traversal (3D-DDA that walks a few occupied voxels ahead of the tests,
// keeps those whose content box the ray crosses and prefetches them; per
// voxel, the packets' boxes, then a 4-wide sign test in front of the scalar
// triangle test for the packets they pass and the ray enters before the
// best hit so far; mailboxing).
//
// Why the grid returns exactly brute force's hit. Traversal keeps the best
// hit over every triangle tested so far (by closerThan) and stops after the
// first voxel whose exit distance is >= that hit's t. This is exact if every
// triangle X whose computed hit tX is <= the final t is referenced in some
// voxel visited by then. The point P = origin + tX * direction lies in a
// visited voxel (the DDA's boundaries are computed in double and walked in
// 64-bit fixed point, 2^-60 of the ray's stretch in the grid, so they are
// exact far below float rounding), and P lies within the triangle test's
// rounding error of X (the watertight test is backward stable: its t is
// exact for vertices moved by a few float ulps of their distance to the ray
// origin).
// So each triangle is referenced in every voxel within a margin of its
// bounding box (and of the triangle itself, when the overlap test refines
// it: boxes of more than kBoxOnlyVoxels voxels), the margin being 1e-5 of
// the grid's size: well above that error for ray origins up to several grid
// diagonals away. The overlap test's own rounding (double, ~1e-16 of the
// coordinates) moves that margin by nothing that matters. Referencing a
// triangle in more voxels than that only costs tests.
//
// What traversal adds keeps this. The walk runs ahead of the tests, but the
// voxels are tested in its order, and a voxel is skipped only when the best
// hit so far is at or before its entry (then it lies in an earlier voxel,
// which the walk's rule above would have stopped after). The 4-wide test
// drops a triangle only where intersectTriangle itself would return false
// (the same operations, IEEE single precision, lane by lane) or where the
// t it would return is beyond the best hit so far (so could not replace
// it); every other triangle goes through intersectTriangle, which alone
// decides hits. The vertices tested are the mesh's, copied bit for bit.
//
// The boxes skip only triangles whose hit cannot be the answer in that
// voxel. P lies within the test's error e of X's bounding box and (up to
// the DDA's far smaller error) in the voxel V where X is found, so P lies
// at least 2m - e inside X's box grown by 2m (m the reference margin) and
// clipped to V grown by 2m, and so inside every box built from it, however
// rounded outwards onto V's lattice (the build's own rounding, in single
// precision, may move a bound inwards by ~1e-7 of the grid: nothing beside
// m): the ray runs inside the box for a stretch of 2m - e > m either side
// of P (in distance along the axes). So a box test that misses the box only
// where the ray's computed distances stray from the exact ones by less than
// m never skips X in V. The boxes are tested in single precision, from
// per-ray planes rounded to float: errors of a few float ulps of the
// distance to the origin, below m for origins within a few grid diagonals,
// the same condition as above. The same bound lets a closest-hit query skip
// a crossed packet whose box the ray enters, as computed, beyond the best
// hit so far: X, hit at tX in V, lies in a box the ray enters more than
// m - e before tX, and V's entry (the span's start) is before tX too but
// where P lies within rounding of it, and then X is tested in the voxel
// before (P within m of it); so the entry is below tX, and tX beyond the
// best hit cannot win (ties included). A skipped packet or voxel leaves its
// triangles out of the mailbox, so they are still tested where the ray
// crosses their boxes.
//
// Ties (equal t, smaller primitive wins) follow from the same argument: two
// triangles hit at the same t share P, so both are referenced where P is.
#include "common/accel/uniform_grid.h"

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstring>
#include <emmintrin.h>
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
// A triangle whose grown bounding box spans at most this many voxels is
// referenced in all of them, without the triangle-box overlap test.
constexpr uint32_t kBoxOnlyVoxels = 8;
// The build's flag on a triangle's first reference (voxel indices are below
// 512^3 = 2^27).
constexpr uint32_t kFirstVoxel = 0x80000000u;
// Traversal: occupied voxels the walk gathers ahead of the tests, and cache
// lines of triangles and of their boxes prefetched per voxel kept. (3 rather
// than 4 with the cheap walk: a few per cent faster at 10K-500K in
// interleaved runs, 2 no better; no packet prefetch, 0 lines, is slower.)
constexpr int kWalkAhead = 3;
constexpr int kPrefetchLines = 4;
constexpr int kPrefetchBoxLines = 2;
// Slots of a ray's mailbox: with the boxes and the 4-wide test, only a few
// triangles per ray reach the scalar test.
constexpr uint32_t kMailboxSlots = 16;
// Steps of the lattice of the rows' content boxes (VoxelRow: one byte a bound).
constexpr int kLatticeSteps = 255;

// The bounds of the finite coordinates of the vertices: four vertices (12
// floats) at a time in three SSE registers, whose lanes cycle through x, y,
// z. A superset of the bounds of the triangles that can be placed, and one
// sequential read instead of a gather through the indices.
Bounds3 finiteCoordinateBounds(const float* positions, size_t vertexCount) {
  const __m128 infinity = _mm_set1_ps(kInfinity), minusInfinity = _mm_set1_ps(-kInfinity), zero = _mm_setzero_ps();
  __m128 low[3] = {infinity, infinity, infinity}, high[3] = {minusInfinity, minusInfinity, minusInfinity};
  const size_t blocks = vertexCount / 4;
  for (size_t block = 0; block < blocks; ++block) {
    for (int r = 0; r < 3; ++r) {
      const __m128 v = _mm_loadu_ps(positions + 12 * block + 4 * r);
      const __m128 finite = _mm_cmpeq_ps(_mm_sub_ps(v, v), zero);  // x - x is 0 exactly when x is finite
      low[r] = _mm_min_ps(low[r], _mm_or_ps(_mm_and_ps(finite, v), _mm_andnot_ps(finite, infinity)));
      high[r] = _mm_max_ps(high[r], _mm_or_ps(_mm_and_ps(finite, v), _mm_andnot_ps(finite, minusInfinity)));
    }
  }
  alignas(16) float lanesLow[12], lanesHigh[12];
  for (int r = 0; r < 3; ++r) _mm_store_ps(lanesLow + 4 * r, low[r]), _mm_store_ps(lanesHigh + 4 * r, high[r]);
  Bounds3 bounds;
  for (int lane = 0; lane < 12; ++lane) {
    bounds.lo[lane % 3] = std::min(bounds.lo[lane % 3], lanesLow[lane]);
    bounds.hi[lane % 3] = std::max(bounds.hi[lane % 3], lanesHigh[lane]);
  }
  for (size_t i = 12 * blocks; i < 3 * vertexCount; ++i) {
    if (!(positions[i] - positions[i] == 0.0f)) continue;
    bounds.lo[i % 3] = std::min(bounds.lo[i % 3], positions[i]);
    bounds.hi[i % 3] = std::max(bounds.hi[i % 3], positions[i]);
  }
  return bounds;
}

// Whether all six coordinates are finite, as isFinite(a) && isFinite(b),
// branch-free: x - x is 0 exactly when x is finite (NaN otherwise).
inline bool finite(const Vec3& a, const Vec3& b) {
  return (a.x - a.x == 0.0f) & (a.y - a.y == 0.0f) & (a.z - a.z == 0.0f) & (b.x - b.x == 0.0f) &
         (b.y - b.y == 0.0f) & (b.z - b.z == 0.0f);
}

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

namespace {

using grid_traversal::PacketBoxes4;
using grid_traversal::TrianglePacket;
using grid_traversal::TriangleVoxelOverlap;

// floor((coordinate - low) * inverse) clamped to [0, last], by truncation
// of the clamped value (the same for values >= 0; cheaper than floor).
[[gnu::always_inline]] inline uint32_t voxelIndex(double coordinate, double low, double inverse, double last) {
  return static_cast<uint32_t>(std::min(std::max((coordinate - low) * inverse, 0.0), last));
}

// x rounded to float, up (roundUp) or down (roundDown).
inline float roundUp(double x) {
  const float f = float(x);
  return double(f) < x ? std::nextafter(f, kInfinity) : f;
}
inline float roundDown(double x) {
  const float f = float(x);
  return double(f) > x ? std::nextafter(f, -kInfinity) : f;
}

// A box on a voxel's lattice, as the bytes of VoxelRow::low and high: the
// low bounds rounded down, the high bounds up, clamped to the lattice
// (truncation is floor for the clamped values, which are >= 0). In single
// precision, all six at once: the bounds are measured from lattice origins
// rounded to float away from the box (the low bounds' origin up, the high
// bounds' down), so the rounding only grows the box but for the
// subtraction's and the scaling's own, ~1e-7 of the grid or of a step,
// nothing beside the margin (see the top of the file).
class LatticeRounding {
 public:
  explicit LatticeRounding(const std::array<double, 3>& latticeStep)
      : inverseStep4_(_mm_setr_ps(float(1.0 / latticeStep[0]), float(1.0 / latticeStep[1]),
                                  float(1.0 / latticeStep[2]), 0.0f)) {}

  // Bytes 0-3: the low bounds' steps, 4-7: the high bounds'.
  [[gnu::always_inline]] __m128i box(const Vec3& low, const Vec3& high, __m128 originLow, __m128 originHigh) const {
    const __m128 zero4 = _mm_setzero_ps(), top4 = _mm_set1_ps(float(kLatticeSteps));
    const __m128 a = _mm_min_ps(
        _mm_max_ps(_mm_mul_ps(_mm_sub_ps(_mm_setr_ps(low.x, low.y, low.z, 0.0f), originLow), inverseStep4_), zero4),
        top4);
    const __m128 b = _mm_min_ps(
        _mm_max_ps(_mm_mul_ps(_mm_sub_ps(_mm_setr_ps(high.x, high.y, high.z, 0.0f), originHigh), inverseStep4_), zero4),
        top4);
    const __m128i highFloor = _mm_cvttps_epi32(b);
    // Where b is not whole its truncation is one short: subtract the all-ones mask.
    const __m128i highSteps = _mm_sub_epi32(highFloor, _mm_castps_si128(_mm_cmplt_ps(_mm_cvtepi32_ps(highFloor), b)));
    return _mm_packus_epi16(_mm_packs_epi32(_mm_cvttps_epi32(a), highSteps), _mm_setzero_si128());
  }

 private:
  __m128 inverseStep4_;
};

// Writes a lattice box (LatticeRounding::box) as packet `packet`'s box.
inline void setPacketBox(PacketBoxes4* packetBoxes, uint32_t packet, __m128i box) {
  const uint64_t bytes = uint64_t(_mm_cvtsi128_si64(box));
  PacketBoxes4& boxes = packetBoxes[packet / 4];
  for (int axis = 0; axis < 3; ++axis) {
    boxes.low[axis][packet % 4] = uint8_t(bytes >> (8 * axis));
    boxes.high[axis][packet % 4] = uint8_t(bytes >> (32 + 8 * axis));
  }
}

}  // namespace

// The build's passes, in order; each leaves in the builder what the next
// one reads, and writes the grid's own arrays as it goes.
class UniformGrid::Builder {
 public:
  Builder(UniformGrid& grid, const MeshView& mesh)
      : grid_(grid), mesh_(mesh), triangleCount_(static_cast<uint32_t>(mesh.triangleCount)) {}

  void placeGrid(const Bounds3& vertexBounds, const UniformGridOptions& options);
  void listReferences();
  void rankVoxels();
  void sortByVoxel();
  void writePackets();
  void recordStats();

 private:
  __m128i writeVoxelPackets(uint32_t reference, uint32_t end, __m128 originLow, __m128 originHigh,
                            const LatticeRounding& lattice, TrianglePacket*& packet, Vec3& packetLow,
                            Vec3& packetHigh);

  UniformGrid& grid_;
  const MeshView& mesh_;
  const uint32_t triangleCount_;
  double margin_ = 0;  // the reference margin (see the top of the file)
  uint64_t voxelCount_ = 0;
  // Per voxel: its references (listReferences), then its first place in
  // sorted_ (rankVoxels), then its end there (sortByVoxel).
  std::vector<uint32_t> counts_;
  // Each reference is its voxel, flagged (kFirstVoxel) where a triangle's
  // references begin: the primitive ids follow from the order, with the
  // triangles left out (not finite, or in no voxel) listed apart.
  std::vector<uint32_t, grid_traversal::LargeArrayAllocator<uint32_t>> references_;
  size_t referenceCount_ = 0;
  std::vector<uint32_t> leftOut_;
  std::vector<uint32_t> sorted_;  // the primitives, by voxel
  uint64_t packetTotal_ = 0;      // at most; shared packets leave some unused
  uint32_t occupiedTotal_ = 0;
};

// The grid's box: the bounds padded on every axis, so flat bounds get a
// thickness and no triangle touches a face of the grid; its resolution, and
// the lattice of the rows' content boxes.
void UniformGrid::Builder::placeGrid(const Bounds3& vertexBounds, const UniformGridOptions& options) {
  UniformGrid& grid = grid_;
  const Vec3 extent = vertexBounds.diagonal();
  double scale = maxComponent(extent);
  if (scale == 0.0) {
    // Every vertex is the same point: any small box will do.
    const Vec3 magnitude = max(-vertexBounds.lo, vertexBounds.hi);
    scale = std::max(1e-6 * maxComponent(magnitude), 1e-30);
  }
  const double padding = kGridPadding * scale;
  for (int axis = 0; axis < 3; ++axis) {
    grid.low_[axis] = double(vertexBounds.lo[axis]) - padding;
    grid.high_[axis] = double(vertexBounds.hi[axis]) + padding;
  }
  const std::array<double, 3> gridExtent{grid.high_[0] - grid.low_[0], grid.high_[1] - grid.low_[1],
                                         grid.high_[2] - grid.low_[2]};
  grid.resolution_ = options.resolution > 0
                         ? resolutionFromLongestAxis(gridExtent, options.resolution)
                         : automaticGridResolution(gridExtent, triangleCount_, options.density);
  for (int axis = 0; axis < 3; ++axis) {
    grid.voxelSize_[axis] = gridExtent[axis] / grid.resolution_[axis];
    grid.inverseVoxelSize_[axis] = grid.resolution_[axis] / gridExtent[axis];
  }
  margin_ = kReferenceMargin * std::max({gridExtent[0], gridExtent[1], gridExtent[2]});
  grid.contentMargin_ = 2 * margin_;
  for (int axis = 0; axis < 3; ++axis)
    grid.latticeStep_[axis] = (grid.voxelSize_[axis] + 2 * grid.contentMargin_) / kLatticeSteps;
  voxelCount_ = uint64_t(grid.resolution_[0]) * grid.resolution_[1] * grid.resolution_[2];
}

// Pass 1: the voxels of every triangle, in increasing primitive order,
// counted per voxel. A triangle is referenced in every voxel its bounding
// box, grown by the margin, touches; where that box spans more than
// kBoxOnlyVoxels voxels and at least two axes, only in those the triangle
// itself (grown by the margin) overlaps. Referencing more voxels than the
// triangle touches costs only tests, never exactness (see the top of the
// file). Locals rather than members in the loop: they stay in registers.
void UniformGrid::Builder::listReferences() {
  const UniformGrid& grid = grid_;
  const MeshView& mesh = mesh_;
  const uint32_t triangleCount = triangleCount_;
  const double margin = margin_;
  const Double3 voxelHalfSize{0.5 * grid.voxelSize_[0] + margin, 0.5 * grid.voxelSize_[1] + margin,
                              0.5 * grid.voxelSize_[2] + margin};
  const uint32_t strideY = uint32_t(grid.resolution_[0]);
  const uint32_t strideZ = uint32_t(grid.resolution_[0]) * uint32_t(grid.resolution_[1]);
  const double lowX = grid.low_[0], lowY = grid.low_[1], lowZ = grid.low_[2];
  const double inverseX = grid.inverseVoxelSize_[0], inverseY = grid.inverseVoxelSize_[1],
               inverseZ = grid.inverseVoxelSize_[2];
  const double lastX = grid.resolution_[0] - 1, lastY = grid.resolution_[1] - 1, lastZ = grid.resolution_[2] - 1;

  std::vector<uint32_t> counts(voxelCount_, 0);
  // Uninitialised, grown by hand: push_back's checks cost more than the rest
  // of a one-voxel triangle's work.
  std::vector<uint32_t, grid_traversal::LargeArrayAllocator<uint32_t>> references;
  std::vector<uint32_t> leftOut;
  size_t referenceCount = 0;
  references.resize(2 * size_t(triangleCount) + 1024);
  Bounds3 meshBounds;
  uint32_t first = kFirstVoxel;  // the flag for the triangle's next reference
  const auto add = [&](uint32_t voxel) {
    if (referenceCount == references.size()) [[unlikely]]
      references.resize(2 * referenceCount);
    ++counts[voxel];
    references[referenceCount++] = voxel | first;
    first = 0;
  };
  for (uint32_t primitive = 0; primitive < triangleCount; ++primitive) {
    if (first == 0) first = kFirstVoxel;  // the previous triangle was placed
    else if (primitive > 0) leftOut.push_back(primitive - 1);
    Vec3 v0, v1, v2;
    mesh.triangle(primitive, v0, v1, v2);
    const Vec3 lo = min(v0, min(v1, v2)), hi = max(v0, max(v1, v2));
    if (!finite(lo, hi)) continue;
    meshBounds.extend(Bounds3(lo, hi));
    const uint32_t x0 = voxelIndex(double(lo.x) - margin, lowX, inverseX, lastX);
    const uint32_t x1 = voxelIndex(double(hi.x) + margin, lowX, inverseX, lastX);
    const uint32_t y0 = voxelIndex(double(lo.y) - margin, lowY, inverseY, lastY);
    const uint32_t y1 = voxelIndex(double(hi.y) + margin, lowY, inverseY, lastY);
    const uint32_t z0 = voxelIndex(double(lo.z) - margin, lowZ, inverseZ, lastZ);
    const uint32_t z1 = voxelIndex(double(hi.z) + margin, lowZ, inverseZ, lastZ);
    if (x0 == x1 && y0 == y1 && z0 == z1) {  // the common case: one voxel
      add(x0 + strideY * y0 + strideZ * z0);
      continue;
    }
    const uint32_t boxVoxels = (x1 - x0 + 1) * (y1 - y0 + 1) * (z1 - z0 + 1);
    const int spannedAxes = (x1 > x0) + (y1 > y0) + (z1 > z0);
    // A box one voxel thick on two axes is a row of voxels, and a connected
    // triangle spanning the row overlaps all of them.
    if (spannedAxes < 2 || boxVoxels <= kBoxOnlyVoxels) {
      for (uint32_t z = z0; z <= z1; ++z)
        for (uint32_t y = y0; y <= y1; ++y)
          for (uint32_t x = x0; x <= x1; ++x) add(x + strideY * y + strideZ * z);
      continue;
    }
    const TriangleVoxelOverlap overlap(v0, v1, v2, voxelHalfSize);
    for (uint32_t z = z0; z <= z1; ++z) {
      const double centerZ = lowZ + (z + 0.5) * grid.voxelSize_[2];
      for (uint32_t y = y0; y <= y1; ++y) {
        const double centerY = lowY + (y + 0.5) * grid.voxelSize_[1];
        for (uint32_t x = x0; x <= x1; ++x)
          if (overlap.overlaps(lowX + (x + 0.5) * grid.voxelSize_[0], centerY, centerZ))
            add(x + strideY * y + strideZ * z);
      }
    }
  }
  if (first != 0 && triangleCount > 0) leftOut.push_back(triangleCount - 1);
  grid_.meshBounds_ = meshBounds;
  counts_ = std::move(counts);
  references_ = std::move(references);
  referenceCount_ = referenceCount;
  leftOut_ = std::move(leftOut);
}

// The occupancy bits and the rows' ranks: counts_[voxel] becomes the
// voxel's first place in sorted_.
void UniformGrid::Builder::rankVoxels() {
  if (referenceCount_ > std::numeric_limits<uint32_t>::max())
    throw std::invalid_argument("grid: more than 2^32 triangle references; use a lower res");
  std::vector<uint64_t>& occupied = grid_.occupied_;
  occupied.assign((voxelCount_ + 63) / 64, 0);
  uint32_t* const counts = counts_.data();
  uint64_t packetTotal = 0;
  uint32_t referenceTotal = 0, occupiedTotal = 0;
  for (uint64_t word = 0; word < occupied.size(); ++word) {
    const uint64_t end = std::min<uint64_t>(voxelCount_, (word + 1) * 64);
    uint64_t bits = 0;
    for (uint64_t voxel = word * 64; voxel < end; ++voxel) {
      const uint32_t count = counts[voxel];
      bits |= uint64_t(count != 0) << (voxel % 64);
      counts[voxel] = referenceTotal;
      referenceTotal += count;
      packetTotal += (count + 3) / 4;
    }
    occupied[word] = bits;
    occupiedTotal += uint32_t(std::popcount(bits));
  }
  if (packetTotal > std::numeric_limits<uint32_t>::max())
    throw std::invalid_argument("grid: more than 2^32 triangle packets; use a lower res");
  packetTotal_ = packetTotal;
  occupiedTotal_ = occupiedTotal;
}

// Pass 2, a counting sort: the primitives by voxel (4-byte writes to an
// array small enough to stay in cache). References come in increasing
// primitive order, so each voxel's list is increasing. After it,
// counts_[v] is voxel v's end in sorted_.
void UniformGrid::Builder::sortByVoxel() {
  const uint64_t total = referenceCount_;
  std::vector<uint32_t> sorted(total);
  uint32_t* const counts = counts_.data();
  const uint32_t* const references = references_.data();
  leftOut_.push_back(kNoPrimitive);  // a sentinel: no placed primitive has that id
  const uint32_t* nextLeftOut = leftOut_.data();
  uint32_t primitive = kNoPrimitive;  // + 1 wraps to 0 at the first reference
  for (uint64_t r = 0; r < total; ++r) {
    const uint32_t reference = references[r];
    primitive += reference >> 31;  // kFirstVoxel: the next placed triangle's
    while (primitive == *nextLeftOut) [[unlikely]] ++primitive, ++nextLeftOut;
    sorted[counts[reference & ~kFirstVoxel]++] = primitive;
  }
  sorted_ = std::move(sorted);
}

// Pass 3: the rows and the packets, written in order, voxel by voxel; each
// voxel's last packet padded with copies of its last triangle (tested
// once: the mailbox). A packet's box: the union of its triangles'
// bounding boxes grown by contentMargin_, clipped to the voxel grown by as
// much (the ends of the lattice), rounded outwards to the lattice; the
// row's box, the union of its packets'. A voxel whose triangles fit in one
// packet and are those of the voxel before it (a run of voxels along a
// floor, a wall or a ceiling: most of the occupied voxels of a room) shares
// that voxel's packet, whose box then spans the whole lattice (the rows'
// boxes, each on its own voxel's lattice, do the culling).
void UniformGrid::Builder::writePackets() {
  UniformGrid& grid = grid_;
  const LatticeRounding lattice(grid.latticeStep_);
  // One row per voxel, indexed by the voxel: an empty voxel's row is never
  // read (its occupancy bit is clear), so it is left unwritten.
  grid.rows_.resize(voxelCount_);
  // At most packetTotal_ packets; the shared ones are left off at the end.
  // Boxes of packets beyond the last are zeros (never read: masked off).
  grid.packets_.resize(packetTotal_);
  grid.packetBoxes_.resize((packetTotal_ + 3) / 4);
  std::memset(static_cast<void*>(grid.packetBoxes_.data()), 0, grid.packetBoxes_.size() * sizeof(PacketBoxes4));
  PacketBoxes4* const packetBoxes = grid.packetBoxes_.data();
  const __m128i wholeLattice = _mm_set_epi32(0, 0, 0x00ffffff, 0);
  const uint32_t strideY = uint32_t(grid.resolution_[0]);
  const uint32_t strideZ = uint32_t(grid.resolution_[0]) * uint32_t(grid.resolution_[1]);
  const uint32_t* const sorted = sorted_.data();
  const uint32_t* const counts = counts_.data();
  TrianglePacket* const firstPacket = grid.packets_.data();
  TrianglePacket* packet = firstPacket;
  VoxelRow* const rows = grid.rows_.data();
  VoxelRow* previousRow = nullptr;
  uint32_t reference = 0, previousReference = 0;
  Vec3 packetLow, packetHigh;  // the last packet's bounds
  for (uint64_t word = 0; word < grid.occupied_.size(); ++word) {
    for (uint64_t bits = grid.occupied_[word]; bits != 0; bits &= bits - 1) {
      const uint32_t voxel = uint32_t(word * 64 + uint64_t(std::countr_zero(bits)));
      VoxelRow* const row = rows + voxel;
      const uint32_t end = counts[voxel];
      // The voxel's lattice origins, rounded away from its boxes.
      const uint32_t cell[3] = {voxel % strideY, voxel / strideY % uint32_t(grid.resolution_[1]), voxel / strideZ};
      float originLow[4] = {}, originHigh[4] = {};
      for (int axis = 0; axis < 3; ++axis) {
        const double latticeLow = grid.low_[axis] + cell[axis] * grid.voxelSize_[axis] - grid.contentMargin_;
        originLow[axis] = roundUp(latticeLow + grid.contentMargin_);
        originHigh[axis] = roundDown(latticeLow - grid.contentMargin_);
      }
      const __m128 low4 = _mm_loadu_ps(originLow), high4 = _mm_loadu_ps(originHigh);
      const uint32_t count = end - reference;
      __m128i rowBox;
      if (count <= 4 && count == reference - previousReference &&
          std::equal(&sorted[reference], &sorted[end], &sorted[previousReference])) {
        // Shared with the occupied voxel before, whose packet was the last written.
        row->firstPacket = previousRow->firstPacket;
        row->endPacket = previousRow->endPacket;
        setPacketBox(packetBoxes, row->firstPacket, wholeLattice);
        rowBox = lattice.box(packetLow, packetHigh, low4, high4);
      } else {
        row->firstPacket = uint32_t(packet - firstPacket);
        rowBox = writeVoxelPackets(reference, end, low4, high4, lattice, packet, packetLow, packetHigh);
        row->endPacket = uint32_t(packet - firstPacket);
      }
      _mm_storel_epi64(reinterpret_cast<__m128i*>(row->low), rowBox);
      previousReference = reference;
      previousRow = row;
      reference = end;
    }
  }
  grid.packets_.resize(size_t(packet - firstPacket));
  grid.packetBoxes_.resize((grid.packets_.size() + 3) / 4);
}

// The packets of one voxel, sorted_[reference .. end), from `packet` on
// (left after them), with their boxes; returns the row's box, and leaves
// the last packet's bounds in packetLow and packetHigh.
inline __m128i UniformGrid::Builder::writeVoxelPackets(uint32_t reference, uint32_t end, __m128 originLow,
                                                       __m128 originHigh, const LatticeRounding& lattice,
                                                       TrianglePacket*& packet, Vec3& packetLow, Vec3& packetHigh) {
  const MeshView& mesh = mesh_;
  const uint32_t* const sorted = sorted_.data();
  const TrianglePacket* const firstPacket = grid_.packets_.data();
  PacketBoxes4* const packetBoxes = grid_.packetBoxes_.data();
  __m128i rowLow = _mm_set1_epi8(char(0xff)), rowHigh = _mm_setzero_si128();
  for (uint32_t r = reference; r < end; r += 4, ++packet) {
    packetLow = Vec3(kInfinity), packetHigh = Vec3(-kInfinity);
    for (uint32_t lane = 0; lane < 4; ++lane) {
      const uint32_t primitive = sorted[std::min(r + lane, end - 1)];
      Vec3 v0, v1, v2;
      mesh.triangle(primitive, v0, v1, v2);
      packet->v[0][0][lane] = v0.x, packet->v[0][1][lane] = v0.y, packet->v[0][2][lane] = v0.z;
      packet->v[1][0][lane] = v1.x, packet->v[1][1][lane] = v1.y, packet->v[1][2][lane] = v1.z;
      packet->v[2][0][lane] = v2.x, packet->v[2][1][lane] = v2.y, packet->v[2][2][lane] = v2.z;
      packet->primitive[lane] = primitive;
      packetLow = min(packetLow, min(v0, min(v1, v2)));
      packetHigh = max(packetHigh, max(v0, max(v1, v2)));
    }
    const __m128i box = lattice.box(packetLow, packetHigh, originLow, originHigh);
    setPacketBox(packetBoxes, uint32_t(packet - firstPacket), box);
    rowLow = _mm_min_epu8(rowLow, box);
    rowHigh = _mm_max_epu8(rowHigh, box);
  }
  // Bytes 0-3: low bounds, 4-7: high bounds (the minima of the first, the maxima of the second).
  const __m128i lowHalf = _mm_set_epi32(0, 0, 0, -1);
  return _mm_or_si128(_mm_and_si128(lowHalf, rowLow), _mm_andnot_si128(lowHalf, rowHigh));
}

void UniformGrid::Builder::recordStats() {
  UniformGrid& grid = grid_;
  AcceleratorStats& stats = grid.stats_;
  stats.leaves = occupiedTotal_;
  stats.nodes = voxelCount_;
  stats.emptyLeaves = voxelCount_ - stats.leaves;
  stats.triangleReferences = referenceCount_;
  stats.averageDepth = 1;
  stats.maxDepth = 1;
  // (The packets' and their boxes' capacity beyond their size, left by
  // shared packets, is never touched, so never resident.)
  stats.bytes = sizeof(grid) + grid.occupied_.capacity() * sizeof(uint64_t) +
                grid.rows_.capacity() * sizeof(VoxelRow) + grid.packets_.size() * sizeof(TrianglePacket) +
                grid.packetBoxes_.size() * sizeof(PacketBoxes4);
}

UniformGrid::UniformGrid(const MeshView& mesh, const UniformGridOptions& options, std::string_view spec)
    : mesh_(mesh) {
  const auto start = std::chrono::steady_clock::now();
  if (mesh.triangleCount >= kNoPrimitive)
    throw std::invalid_argument("grid: " + std::to_string(mesh.triangleCount) +
                                " triangles exceed the 32-bit primitive ids; split the cell");
  stats_.spec = std::string(spec);
  // The grid's box holds every triangle that can be placed (triangles with
  // a non-finite vertex cannot be, and are left out: such input should be
  // refused at import): the bounds of the vertices' finite coordinates.
  // (meshBounds_, over the placed triangles alone, comes with pass 1.)
  const Bounds3 vertexBounds =
      mesh.triangleCount == 0 ? Bounds3() : finiteCoordinateBounds(mesh.positions, mesh.vertexCount);
  if (vertexBounds.empty()) {
    stats_.bytes = sizeof(*this);
  } else {
    Builder builder(*this, mesh);
    builder.placeGrid(vertexBounds, options);
    builder.listReferences();
    builder.rankVoxels();
    builder.sortByVoxel();
    builder.writePackets();
    builder.recordStats();
  }
  stats_.buildMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

// ---------------------------------------------------------------------------
// Traversal

namespace {

// Clips [tEnter, tExit] to the grid box [low, high] (slabs), with the
// inverse direction. An axis the ray runs parallel to only decides whether
// the ray is inside the slab at all. False when nothing of the ray is left.
[[gnu::always_inline]] inline bool clipToGrid(const double origin[3], const double direction[3],
                                              const double inverse[3], const std::array<double, 3>& low,
                                              const std::array<double, 3>& high, double& tEnter, double& tExit) {
  if (!(tEnter < tExit)) return false;
  for (int axis = 0; axis < 3; ++axis) {
    if (direction[axis] == 0.0) {
      if (origin[axis] < low[axis] || origin[axis] > high[axis]) return false;
      continue;
    }
    const double a = (low[axis] - origin[axis]) * inverse[axis], b = (high[axis] - origin[axis]) * inverse[axis];
    tEnter = std::max(tEnter, std::min(a, b));
    tExit = std::min(tExit, std::max(a, b));
  }
  return tEnter <= tExit;
}

// Fetches the first cache lines of a voxel's packets and of their boxes.
[[gnu::always_inline]] inline void prefetchVoxel(const TrianglePacket* packets, const PacketBoxes4* packetBoxes,
                                                 uint32_t first, uint32_t end) {
  const char* const boxLine = reinterpret_cast<const char*>(packetBoxes + first / 4);
  const char* const lastBox = reinterpret_cast<const char*>(packetBoxes + (end + 3) / 4) - 1;
  for (int l = 0; l < kPrefetchBoxLines && boxLine + 64 * l <= lastBox; ++l) __builtin_prefetch(boxLine + 64 * l);
  const char* const line = reinterpret_cast<const char*>(packets + first);
  const char* const last = reinterpret_cast<const char*>(packets + end) - 1;
  for (int l = 0; l < kPrefetchLines && line + 64 * l <= last; ++l) __builtin_prefetch(line + 64 * l);
}

// The occupied voxels the walk gathered ahead of the tests (one slot more:
// the walk records every voxel it enters, and keeps the occupied ones).
struct AheadVoxels {
  uint32_t index[kWalkAhead + 1];
  int64_t enter[kWalkAhead + 1], exit[kWalkAhead + 1];  // fixed point (VoxelWalk)
  uint32_t left[kWalkAhead + 1];                        // packed as VoxelWalk::left
};

}  // namespace

// The 3D-DDA. It runs on 64-bit integers: distances beyond tEnter in units
// of 2^-60 of the ray's stretch in the grid (a resolution ~2^-60 of it, far
// finer than double's own after a few hundred additions), because integer
// compares and adds make each step's dependency chain about half as long as
// in double. Distances beyond 2^61 units (a boundary the ray meets only
// after leaving the grid, or never) are held at 2^61: never stepped to, and
// sums stay below 2^63. Scalar members only, so that the compiler keeps
// them in registers.
struct UniformGrid::VoxelWalk {
  static constexpr double kUnits = 0x1p60, kFar = 0x1p61;

  VoxelWalk(const UniformGrid& grid, const double origin[3], const double direction[3], const double inverse[3],
            double tEnter, double tExit, int32_t axisStep[3]);

  int64_t toFixed(double t) const { return int64_t(std::clamp((t - tEnter) * scale, -kFar, kFar)); }
  double distance(int64_t fixed) const { return tEnter + double(fixed) * unit; }

  // Walks on until it has gathered kWalkAhead occupied voxels or left the
  // grid (then `walking` turns false); returns how many it gathered.
  [[gnu::always_inline]] int gather(const uint64_t* occupied, const VoxelRow* rows, const int32_t axisStep[3],
                                    AheadVoxels& ahead, bool& walking);

  double tEnter, scale, unit;
  int32_t index = 0;
  // The steps left per axis, ten bits each (x, y, z from bit 0): at most
  // 511, and 0 for an axis never stepped. One register and one store a
  // step instead of three.
  uint32_t left = 0;
  int64_t tx, ty, tz;                 // the next boundary per axis
  int64_t deltaX, deltaY, deltaZ;     // between boundaries
  int64_t fixedExit;                  // where the walk ends
  int64_t fixedVoxelEnter = 0;        // the current voxel's entry
};

// Set-up: the voxel at the entry point, and per axis the distance to the
// next voxel boundary (tNext), between boundaries (tDelta), the step of the
// voxel index (axisStep), and the steps left before the ray leaves the grid.
inline UniformGrid::VoxelWalk::VoxelWalk(const UniformGrid& grid, const double origin[3], const double direction[3],
                                         const double inverse[3], double tEnter, double tExit, int32_t axisStep[3])
    : tEnter(tEnter) {
  const int32_t strides[3] = {1, grid.resolution_[0], grid.resolution_[0] * grid.resolution_[1]};
  int32_t stepsLeft[3];
  double tNext[3], tDelta[3];
  for (int axis = 0; axis < 3; ++axis) {
    const double entry = origin[axis] + tEnter * direction[axis];
    // floor, clamped to the grid, as truncation of the clamped value (the
    // same for values >= 0; std::floor is a library call on baseline x86-64).
    const double cell = (entry - grid.low_[axis]) * grid.inverseVoxelSize_[axis];
    const int voxel = static_cast<int>(std::clamp(cell, 0.0, double(grid.resolution_[axis] - 1)));
    index += voxel * strides[axis];
    if (direction[axis] > 0.0) {
      axisStep[axis] = strides[axis];
      stepsLeft[axis] = grid.resolution_[axis] - 1 - voxel;
      tNext[axis] = (grid.low_[axis] + (voxel + 1) * grid.voxelSize_[axis] - origin[axis]) * inverse[axis];
      tDelta[axis] = grid.voxelSize_[axis] * inverse[axis];
    } else if (direction[axis] < 0.0) {
      axisStep[axis] = -strides[axis];
      stepsLeft[axis] = voxel;
      tNext[axis] = (grid.low_[axis] + voxel * grid.voxelSize_[axis] - origin[axis]) * inverse[axis];
      tDelta[axis] = -grid.voxelSize_[axis] * inverse[axis];
    } else {
      axisStep[axis] = 0;
      stepsLeft[axis] = std::numeric_limits<int32_t>::max();  // never stepped
      tNext[axis] = std::numeric_limits<double>::infinity();
      tDelta[axis] = 0.0;
    }
  }
  scale = kUnits / std::max(tExit - tEnter, 1e-280);
  unit = 1.0 / scale;
  tx = toFixed(tNext[0]), ty = toFixed(tNext[1]), tz = toFixed(tNext[2]);
  deltaX = int64_t(std::min(tDelta[0] * scale, kFar));
  deltaY = int64_t(std::min(tDelta[1] * scale, kFar));
  deltaZ = int64_t(std::min(tDelta[2] * scale, kFar));
  // The walk needs no check that it stays in the grid: along an axis, the
  // boundary `left` steps on is the grid's face (integer sums are exact),
  // so ending the walk there at the latest ends it in the last voxel. (The
  // set-up's rounding may put that face a little before tExit.)
  const auto face = [](int64_t next, int64_t delta, int32_t steps) {
    if (steps == std::numeric_limits<int32_t>::max()) return int64_t(kFar);  // never stepped
    return int64_t(std::min<__int128>(__int128(next) + __int128(steps) * delta, __int128(kFar)));
  };
  fixedExit = std::min({toFixed(tExit), face(tx, deltaX, stepsLeft[0]), face(ty, deltaY, stepsLeft[1]),
                        face(tz, deltaZ, stepsLeft[2])});
  const auto leftField = [](int32_t steps) {
    return steps == std::numeric_limits<int32_t>::max() ? 0u : uint32_t(steps);
  };
  left = leftField(stepsLeft[0]) | leftField(stepsLeft[1]) << 10 | leftField(stepsLeft[2]) << 20;
}

inline int UniformGrid::VoxelWalk::gather(const uint64_t* occupied, const VoxelRow* rows, const int32_t axisStep[3],
                                          AheadVoxels& ahead, bool& walking) {
  constexpr uint32_t axisUnit[3] = {1u, 1u << 10, 1u << 20};
  int count = 0;
  for (;;) {
    // The axis whose boundary comes first (ties: x, then y), by
    // conditional moves and masks rather than branches; its boundary is
    // the voxel's exit. (Two compares and selects: half the instructions
    // of masks from three compares, and the walk is bound by them.)
    const bool yBeforeZ = ty <= tz;
    const int64_t exitYZ = yBeforeZ ? ty : tz;
    const bool xFirst = tx <= exitYZ;
    const int64_t fixedVoxelExit = xFirst ? tx : exitYZ;
    const int64_t maskX = -int64_t(xFirst);
    const int64_t maskY = ~maskX & -int64_t(yBeforeZ);
    const int64_t maskZ = ~(maskX | maskY);
    // Recorded always, kept only if occupied: no branch to mispredict.
    ahead.index[count] = uint32_t(index);
    ahead.enter[count] = fixedVoxelEnter;
    ahead.exit[count] = fixedVoxelExit;
    ahead.left[count] = left;
    const uint32_t isOccupied = uint32_t(occupied[uint32_t(index) / 64] >> (uint32_t(index) % 64)) & 1;
    // The row of an occupied voxel, fetched now: it is read once the walk
    // has gathered its voxels. (An empty voxel's points at the first row.)
    __builtin_prefetch(rows + (uint32_t(index) & -isOccupied));
    count += int(isOccupied);
    if (fixedVoxelExit >= fixedExit) {
      walking = false;
      return count;
    }
    // By table: GCC turns a select among three into a branch.
    const unsigned axis = unsigned(!xFirst) << unsigned(!yBeforeZ);  // 0, 1 or 2
    index += axisStep[axis];
    tx += deltaX & maskX;
    ty += deltaY & maskY;
    tz += deltaZ & maskZ;
    left -= axisUnit[axis];
    fixedVoxelEnter = fixedVoxelExit;
    if (count == kWalkAhead) return count;
  }
}

// Content boxes (VoxelRow): along each axis, the ray meets the first plane
// of the current voxel's lattice at latticeOrigin + left * latticeStride
// (left: the walk's steps left along the axis, which number the voxel's
// layer), and each lattice step after it latticeStep later. In single
// precision, four lanes x, y, z and a fourth that carries the voxel's span
// (-inf or +inf, no step). A ray parallel to an axis never meets its
// planes: it tests no boxes (rare; the packets decide alone, as they may).
struct UniformGrid::ContentBoxes {
  using Float4 = grid_traversal::PacketRay::Float4;

  ContentBoxes(const UniformGrid& grid, const double origin[3], const double direction[3], const double inverse[3]);

  // The clip of a voxel's packets' boxes to the part of the ray in the
  // voxel, before tExit, within the row's box; false when that part is
  // empty (the ray misses the row's box there).
  [[gnu::always_inline]] bool clip(const VoxelRow& row, uint32_t packedLeft, double voxelEnter, double voxelExit,
                                   double tExit, grid_traversal::PacketBoxClip& clip) const;

  static Float4 broadcast(float x) { return Float4{x, x, x, x}; }

  bool testBoxes;
  __m128 originLow, originHigh, stride4, step4;
  // The packets' boxes: the same lattice (grid_traversal.h).
  Float4 packetStep[3];
};

inline UniformGrid::ContentBoxes::ContentBoxes(const UniformGrid& grid, const double origin[3],
                                               const double direction[3], const double inverse[3])
    : testBoxes(direction[0] != 0.0 && direction[1] != 0.0 && direction[2] != 0.0) {
  float latticeOrigin[3], latticeStride[3], latticeStep[3];
  for (int axis = 0; axis < 3; ++axis) {
    // The layer: resolution - 1 - left going up the axis, left going down.
    const double layer = direction[axis] > 0.0 ? grid.resolution_[axis] - 1 : 0.0;
    const double stride = (direction[axis] > 0.0 ? -grid.voxelSize_[axis] : grid.voxelSize_[axis]) * inverse[axis];
    latticeOrigin[axis] = float((grid.low_[axis] - grid.contentMargin_ - origin[axis]) * inverse[axis] +
                                layer * grid.voxelSize_[axis] * inverse[axis]);
    latticeStride[axis] = float(stride);
    latticeStep[axis] = float(grid.latticeStep_[axis] * inverse[axis]);
  }
  originLow = _mm_setr_ps(latticeOrigin[0], latticeOrigin[1], latticeOrigin[2], -kInfinity);
  originHigh = _mm_setr_ps(latticeOrigin[0], latticeOrigin[1], latticeOrigin[2], kInfinity);
  stride4 = _mm_setr_ps(latticeStride[0], latticeStride[1], latticeStride[2], 0.0f);
  step4 = _mm_setr_ps(latticeStep[0], latticeStep[1], latticeStep[2], 0.0f);
  for (int axis = 0; axis < 3; ++axis) packetStep[axis] = broadcast(testBoxes ? latticeStep[axis] : 0.0f);
}

inline bool UniformGrid::ContentBoxes::clip(const VoxelRow& row, uint32_t packedLeft, double voxelEnter,
                                            double voxelExit, double tExit,
                                            grid_traversal::PacketBoxClip& clip) const {
  if (testBoxes) {
    const __m128i layerLeft =
        _mm_setr_epi32(int(packedLeft & 1023), int(packedLeft >> 10 & 1023), int(packedLeft >> 20), 0);
    const __m128 layers = _mm_mul_ps(_mm_cvtepi32_ps(layerLeft), stride4);
    const __m128 startLow = _mm_add_ps(originLow, layers), startHigh = _mm_add_ps(originHigh, layers);
    const __m128i zero = _mm_setzero_si128();
    const __m128i bytes = _mm_unpacklo_epi8(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(row.low)), zero);
    const __m128 a = _mm_add_ps(startLow, _mm_mul_ps(_mm_cvtepi32_ps(_mm_unpacklo_epi16(bytes, zero)), step4));
    const __m128 b = _mm_add_ps(startHigh, _mm_mul_ps(_mm_cvtepi32_ps(_mm_unpackhi_epi16(bytes, zero)), step4));
    // The latest entry and the earliest exit over the axes.
    __m128 enterAll = _mm_min_ps(a, b), exitAll = _mm_max_ps(a, b);
    enterAll = _mm_max_ps(enterAll, _mm_shuffle_ps(enterAll, enterAll, _MM_SHUFFLE(1, 0, 3, 2)));
    exitAll = _mm_min_ps(exitAll, _mm_shuffle_ps(exitAll, exitAll, _MM_SHUFFLE(1, 0, 3, 2)));
    enterAll = _mm_max_ss(enterAll, _mm_shuffle_ps(enterAll, enterAll, _MM_SHUFFLE(1, 1, 1, 1)));
    exitAll = _mm_min_ss(exitAll, _mm_shuffle_ps(exitAll, exitAll, _MM_SHUFFLE(1, 1, 1, 1)));
    const float lower = std::max(_mm_cvtss_f32(enterAll), float(voxelEnter));
    const float upper = std::min(_mm_cvtss_f32(exitAll), float(std::min(voxelExit, tExit)));
    if (!(lower <= upper)) return false;
    // The packets' boxes lie in the row's: only [lower, upper] counts.
    alignas(16) float start[4];
    _mm_store_ps(start, startLow);
    for (int axis = 0; axis < 3; ++axis) clip.planeLow[axis] = clip.planeHigh[axis] = broadcast(start[axis]);
    clip.lower = broadcast(lower);
    clip.upper = broadcast(upper);
  } else {
    for (int axis = 0; axis < 3; ++axis) {
      clip.planeLow[axis] = broadcast(-kInfinity);
      clip.planeHigh[axis] = broadcast(kInfinity);
    }
    clip.lower = broadcast(-kInfinity);
    clip.upper = broadcast(kInfinity);
  }
  for (int axis = 0; axis < 3; ++axis) clip.step[axis] = packetStep[axis];
  return true;
}

// The walk runs ahead of the tests: it gathers the next few occupied
// voxels along the ray, keeps those whose content box the ray crosses and
// prefetches their triangles, so that their cache misses overlap instead of
// following one another (the triangles are tested in the walk's order all
// the same). Flattened: the triangle test is inlined into the walk (GCC
// otherwise calls it), which keeps the walk's state in registers.
template <bool AnyHit>
[[gnu::flatten]] bool UniformGrid::traverse(const Ray& ray, Hit& best) const {
  if (packets_.empty() || !hasFiniteOriginAndDirection(ray)) return false;
  const double origin[3] = {ray.origin.x, ray.origin.y, ray.origin.z};
  const double direction[3] = {ray.direction.x, ray.direction.y, ray.direction.z};
  if (direction[0] == 0.0 && direction[1] == 0.0 && direction[2] == 0.0) return false;
  // Distances along the ray are computed with the inverse direction (one
  // division per axis); they differ from quotients by an ulp, far below the
  // reference margin (see the top of the file).
  const double inverse[3] = {1.0 / direction[0], 1.0 / direction[1], 1.0 / direction[2]};
  double tEnter = ray.tMin, tExit = ray.tMax;
  if (!clipToGrid(origin, direction, inverse, low_, high_, tEnter, tExit)) return false;

  int32_t axisStep[3];
  VoxelWalk walk(*this, origin, direction, inverse, tEnter, tExit, axisStep);
  const ContentBoxes contentBoxes(*this, origin, direction, inverse);
  const WatertightRay frame(ray.direction);
  const grid_traversal::PacketRay packetRay(frame, ray);
  grid_traversal::Mailbox<kMailboxSlots> mailbox;
  const TrianglePacket* const packets = packets_.data();
  const PacketBoxes4* const packetBoxes = packetBoxes_.data();
  const uint64_t* const occupied = occupied_.data();
  const VoxelRow* const rows = rows_.data();

  AheadVoxels ahead;
  bool walking = true;
  while (walking) {
    const int count = walk.gather(occupied, rows, axisStep, ahead, walking);
    // The rows, and the content-box test: the part of the ray in the voxel
    // and before the best hit so far must cross the box.
    uint32_t first[kWalkAhead], end[kWalkAhead];
    double enter[kWalkAhead], exit[kWalkAhead];
    grid_traversal::PacketBoxClip clips[kWalkAhead];
    int kept = 0;
    for (int k = 0; k < count; ++k) {
      const VoxelRow& row = rows[ahead.index[k]];
      const double voxelEnter = walk.distance(ahead.enter[k]), voxelExit = walk.distance(ahead.exit[k]);
      if (!contentBoxes.clip(row, ahead.left[k], voxelEnter, voxelExit, tExit, clips[kept])) continue;
      first[kept] = row.firstPacket;
      end[kept] = row.endPacket;
      enter[kept] = voxelEnter;
      exit[kept] = voxelExit;
      prefetchVoxel(packets, packetBoxes, first[kept], end[kept]);
      ++kept;
    }
    for (int k = 0; k < kept; ++k) {
      // A voxel entered at or beyond the best hit cannot hold a nearer one;
      // nor can any voxel after the one holding it. (Hits beyond the current
      // voxel are kept, not re-tested: the mailbox would skip them.)
      if constexpr (!AnyHit) {
        if (best.found() && double(best.t) <= enter[k]) return true;
      }
      if (grid_traversal::testPackets<AnyHit>(packets, packetBoxes, first[k], end[k], clips[k], mailbox, packetRay,
                                              frame, ray, best))
        return true;
      if constexpr (!AnyHit) {
        if (best.found() && double(best.t) <= exit[k]) return true;
      }
    }
    if constexpr (!AnyHit) {
      if (best.found() && double(best.t) < tExit) {
        tExit = double(best.t);
        walk.fixedExit = std::min(walk.fixedExit, walk.toFixed(tExit));
      }
    }
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
