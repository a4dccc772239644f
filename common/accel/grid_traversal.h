// The pieces `grid` and `hgrid` share: the ray clipped to the grid's box, a
// voxel's triangles tested through a mailbox (as references into the mesh,
// or as 4-wide packets of copied vertices behind their boxes), and for the
// builds the triangle-voxel overlap test and an allocator for large arrays.
// Inline: the tests sit in the innermost loop of tracing.
#pragma once

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <emmintrin.h>
#include <new>
#include <utility>

#include "common/accel/triangle_intersect.h"
#include "common/mesh_view.h"
#include "common/triangle_box_overlap.h"
#include "common/ray.h"

namespace portico::grid_traversal {

// Clips [tEnter, tExit] to the box [low, high] (slabs). An axis the ray runs
// parallel to only decides whether the ray is inside the slab at all. False
// when nothing of the ray is left.
inline bool clipToBox(const double origin[3], const double direction[3], const double low[3], const double high[3],
                      double& tEnter, double& tExit) {
  if (!(tEnter < tExit)) return false;
  for (int axis = 0; axis < 3; ++axis) {
    if (direction[axis] == 0.0) {
      if (origin[axis] < low[axis] || origin[axis] > high[axis]) return false;
      continue;
    }
    double tNear = (low[axis] - origin[axis]) / direction[axis];
    double tFar = (high[axis] - origin[axis]) / direction[axis];
    if (tNear > tFar) std::swap(tNear, tFar);
    tEnter = std::max(tEnter, tNear);
    tExit = std::min(tExit, tFar);
  }
  return tEnter <= tExit;
}

// A direct-mapped cache of the primitives tested last, one per query (on
// the stack, so concurrent queries share nothing): a triangle spanning
// several voxels is tested once, its result does not depend on the voxel.
// Slots: a power of two; a collision only repeats a test.
template <uint32_t Slots>
class Mailbox {
 public:
  Mailbox() { std::memset(slots_, 0xff, sizeof(slots_)); }   // kNoPrimitive everywhere
  // True the first time `primitive` is seen (recently); it is then recorded.
  bool firstVisit(uint32_t primitive) {
    uint32_t& slot = slots_[primitive & (Slots - 1)];
    if (slot == primitive) return false;
    slot = primitive;
    return true;
  }

 private:
  static_assert((Slots & (Slots - 1)) == 0);
  uint32_t slots_[Slots];
};

// Four triangles as a grid stores them, side by side per coordinate
// (vertex, axis, lane), with their primitive ids: a voxel's triangles are
// copied (bit for bit) from the mesh into its own run of packets, the last
// one padded with copies of the voxel's last triangle.
struct TrianglePacket {
  float v[3][3][4];
  uint32_t primitive[4];
};
static_assert(sizeof(TrianglePacket) == 160);

// The boxes of four consecutive packets (block b: packets 4b .. 4b + 3),
// each the box of its four triangles on the lattice of its voxel's content
// box (uniform_grid.h): low[axis][packet], high[axis][packet]. Kept apart
// from the packets, side by side, so that testing a voxel's boxes reads a
// line or two, four boxes at a time, and only the packets whose box the ray
// crosses are loaded.
struct PacketBoxes4 {
  uint8_t low[3][4], high[3][4];
};
static_assert(sizeof(PacketBoxes4) == 24);

// For the builds of `grid` and `hgrid`: the separating-axis test of
// triangleOverlapsBoxBeyondBounds (the 9 edge cross products and the
// triangle's plane), set up once per triangle so that each voxel costs a dot
// product per axis: the triangle's projections and the
// box's radius on each axis do not depend on the voxel. In double, from float
// vertices; the rounding (far below 1e-12 of the coordinates) is nothing
// beside the reference margin the box is grown by, so the test stays
// conservative in the sense the exactness argument needs.
struct TriangleVoxelOverlap {
  static constexpr int kAxes = 10;
  double axis[kAxes][3];
  double low[kAxes], high[kAxes];  // the triangle's projection, minus the box radius / plus it

  TriangleVoxelOverlap() = default;
  TriangleVoxelOverlap(const Vec3& v0, const Vec3& v1, const Vec3& v2, const Double3& halfSize) {
    const Double3 a = toDouble(v0), b = toDouble(v1), c = toDouble(v2);
    const Double3 edges[3] = {b - a, c - b, a - c};
    int k = 0;
    for (const Double3& e : edges) {
      set(k++, 0.0, -e.z, e.y);
      set(k++, e.z, 0.0, -e.x);
      set(k++, -e.y, e.x, 0.0);
    }
    const Double3 normal = cross(edges[0], edges[1]);
    set(k, normal.x, normal.y, normal.z);
    for (k = 0; k < kAxes; ++k) {
      const double pa = axis[k][0] * a.x + axis[k][1] * a.y + axis[k][2] * a.z;
      const double pb = axis[k][0] * b.x + axis[k][1] * b.y + axis[k][2] * b.z;
      const double pc = axis[k][0] * c.x + axis[k][1] * c.y + axis[k][2] * c.z;
      const double radius = halfSize.x * std::fabs(axis[k][0]) + halfSize.y * std::fabs(axis[k][1]) +
                            halfSize.z * std::fabs(axis[k][2]);
      low[k] = std::min({pa, pb, pc}) - radius;
      high[k] = std::max({pa, pb, pc}) + radius;
    }
  }
  void set(int k, double x, double y, double z) { axis[k][0] = x, axis[k][1] = y, axis[k][2] = z; }

  // Whether the box centred at `center` (of the half size given above)
  // overlaps the triangle: no axis separates them.
  bool overlaps(double x, double y, double z) const {
    for (int k = 0; k < kAxes; ++k) {
      const double d = axis[k][0] * x + axis[k][1] * y + axis[k][2] * z;
      if (d < low[k] || d > high[k]) return false;
    }
    return true;
  }
};

// Allocator for a grid's large arrays: elements are left uninitialised (the
// build writes every one). No huge pages: madvise(MADV_HUGEPAGE) makes a
// build in isolation up to 2x faster (fewer TLB misses in the counting sort),
// but in a worker, where every cell's grid lands on fresh memory, the kernel
// zeroing 2 MiB pages takes 15-20 % of the worker's CPU and the photon pass
// runs ~20 % slower (docs/pipeline-benchmark.md).
template <typename T>
struct LargeArrayAllocator {
  using value_type = T;

  LargeArrayAllocator() = default;
  template <typename U>
  LargeArrayAllocator(const LargeArrayAllocator<U>&) noexcept {}

  T* allocate(size_t count) { return static_cast<T*>(::operator new(count * sizeof(T))); }
  void deallocate(T* pointer, size_t) noexcept { ::operator delete(pointer); }
  template <typename U>
  void construct(U* pointer) noexcept {
    ::new (static_cast<void*>(pointer)) U;
  }
  template <typename U, typename... Arguments>
  void construct(U* pointer, Arguments&&... arguments) {
    ::new (static_cast<void*>(pointer)) U(std::forward<Arguments>(arguments)...);
  }
  template <typename U>
  bool operator==(const LargeArrayAllocator<U>&) const noexcept { return true; }
};

// The ray as the packet test needs it: its origin and shear broadcast to the
// four lanes, in the watertight test's frame.
struct PacketRay {
  using Float4 = float __attribute__((vector_size(16)));
  Float4 originX, originY, originZ;  // origin[kx], origin[ky], origin[kz]
  Float4 shearX, shearY, scaleZ;     // Sx, Sy, Sz
  Float4 tMin, tMax;
  int kx, ky, kz;

  PacketRay(const WatertightRay& frame, const Ray& ray) : kx(frame.kx), ky(frame.ky), kz(frame.kz) {
    const float origin[3] = {ray.origin.x, ray.origin.y, ray.origin.z};
    const auto broadcast = [](float x) { return Float4{x, x, x, x}; };  // bit for bit, -0 included
    originX = broadcast(origin[kx]);
    originY = broadcast(origin[ky]);
    originZ = broadcast(origin[kz]);
    shearX = broadcast(frame.Sx);
    shearY = broadcast(frame.Sy);
    scaleZ = broadcast(frame.Sz);
    tMin = broadcast(ray.tMin);
    tMax = broadcast(ray.tMax);
  }
};

// Where a ray crosses the lattice of a voxel's packet boxes, as distances
// along it (each value broadcast to the four lanes): lattice coordinate q of
// axis a at planeLow[a] + q * step[a] for the boxes' low sides, planeHigh[a]
// + q * step[a] for their high sides (planeLow = planeHigh, but for a ray
// that tests no boxes: -inf and +inf, and no step); lower to upper, the span
// of the ray that counts.
struct PacketBoxClip {
  PacketRay::Float4 planeLow[3], planeHigh[3], step[3];
  PacketRay::Float4 lower, upper;
};

// intersectTriangle's own steps (translation, shear, edge functions, sign
// test, det, T and t = T / det) on the four lanes of a packet, with the very
// operations of the scalar test, so each lane gets the scalar test's U, V,
// W, det and t bit for bit.
struct PacketLanes {
  using Int4 = int32_t __attribute__((vector_size(16)));
  PacketRay::Float4 t, det, V, W;
  Int4 candidate;  // all ones: the lane may hit (see packetCandidates)
  Int4 anyZero;    // all ones: an edge function is exactly zero
};

template <bool AnyHit>
inline PacketLanes packetLanes(const TrianglePacket& packet, const PacketRay& packetRay, float bestT) {
  using Float4 = PacketRay::Float4;
  using Int4 = PacketLanes::Int4;
  const auto load = [](const float* p) {
    Float4 value;
    std::memcpy(&value, p, sizeof(value));
    return value;
  };
  const int kx = packetRay.kx, ky = packetRay.ky, kz = packetRay.kz;
  const Float4 az = load(packet.v[0][kz]) - packetRay.originZ;
  const Float4 bz = load(packet.v[1][kz]) - packetRay.originZ;
  const Float4 cz = load(packet.v[2][kz]) - packetRay.originZ;
  const Float4 Ax = (load(packet.v[0][kx]) - packetRay.originX) - packetRay.shearX * az;
  const Float4 Ay = (load(packet.v[0][ky]) - packetRay.originY) - packetRay.shearY * az;
  const Float4 Bx = (load(packet.v[1][kx]) - packetRay.originX) - packetRay.shearX * bz;
  const Float4 By = (load(packet.v[1][ky]) - packetRay.originY) - packetRay.shearY * bz;
  const Float4 Cx = (load(packet.v[2][kx]) - packetRay.originX) - packetRay.shearX * cz;
  const Float4 Cy = (load(packet.v[2][ky]) - packetRay.originY) - packetRay.shearY * cz;
  PacketLanes lanes;
  const Float4 U = Cx * By - Cy * Bx;
  lanes.V = Ax * Cy - Ay * Cx;
  lanes.W = Bx * Ay - By * Ax;
  const Float4 zero{};
  const Int4 negative = (U < zero) | (lanes.V < zero) | (lanes.W < zero);
  const Int4 positive = (U > zero) | (lanes.V > zero) | (lanes.W > zero);
  lanes.anyZero = (U == zero) | (lanes.V == zero) | (lanes.W == zero);
  // Most packets end here: no lane passes the sign test nor needs the
  // double-precision decision, so none can be a candidate whatever t is.
  const Int4 signsAgree = ~(negative & positive) | lanes.anyZero;
  if (_mm_movemask_ps(reinterpret_cast<__m128>(signsAgree)) == 0) {
    lanes.candidate = Int4{};
    return lanes;
  }
  lanes.det = U + lanes.V + lanes.W;
  const Float4 T =
      U * (packetRay.scaleZ * az) + lanes.V * (packetRay.scaleZ * bz) + lanes.W * (packetRay.scaleZ * cz);
  lanes.t = T / lanes.det;
  Int4 inRange = (lanes.t > packetRay.tMin) & (lanes.t < packetRay.tMax);
  if constexpr (!AnyHit) inRange &= lanes.t <= Float4{bestT, bestT, bestT, bestT};
  lanes.candidate = (signsAgree & inRange) | lanes.anyZero;
  return lanes;
}

// Bit k set where lane k of the mask is.
inline unsigned laneBits(PacketLanes::Int4 mask) {
  return unsigned(_mm_movemask_ps(reinterpret_cast<__m128>(mask)));   // every lane is all ones or zero
}

// The lanes of `packet` that may hit (bit k: lane k). A lane is dropped
// only where intersectTriangle would return false on the same sign test or
// the same check of t against [tMin, tMax], or (closest hit) where its t is
// beyond bestT, so could not win under closerThan. Lanes with an edge
// function exactly zero, which the scalar test re-decides in double, are kept.
template <bool AnyHit>
inline unsigned packetCandidates(const TrianglePacket& packet, const PacketRay& packetRay, float bestT) {
  return laneBits(packetLanes<AnyHit>(packet, packetRay, bestT).candidate);
}

// Which of the four boxes the ray crosses within the span of the clip (bit k:
// packet 4b + k); entries[k]: where the ray enters box k within that span
// (the latest entry over the axes and the span's start). SSE2 (the x86-64 baseline), which GCC's vector extensions
// do not reach here: they widen the bytes one by one.
inline unsigned crossedPacketBoxes(const PacketBoxes4& boxes, const PacketBoxClip& clip, float* entries) {
  const __m128i zero = _mm_setzero_si128();
  // low x, y, z, high x (16 bytes), then high y, z (8 bytes), widened to 16 then 32 bits.
  const __m128i first = _mm_loadu_si128(reinterpret_cast<const __m128i*>(&boxes));
  const __m128i second = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(&boxes.high[1]));
  const __m128i lowXY = _mm_unpacklo_epi8(first, zero), lowZhighX = _mm_unpackhi_epi8(first, zero);
  const __m128i highYZ = _mm_unpacklo_epi8(second, zero);
  const __m128 low[3] = {_mm_cvtepi32_ps(_mm_unpacklo_epi16(lowXY, zero)),
                         _mm_cvtepi32_ps(_mm_unpackhi_epi16(lowXY, zero)),
                         _mm_cvtepi32_ps(_mm_unpacklo_epi16(lowZhighX, zero))};
  const __m128 high[3] = {_mm_cvtepi32_ps(_mm_unpackhi_epi16(lowZhighX, zero)),
                          _mm_cvtepi32_ps(_mm_unpacklo_epi16(highYZ, zero)),
                          _mm_cvtepi32_ps(_mm_unpackhi_epi16(highYZ, zero))};
  // The latest entry and the earliest exit over the axes and the span.
  __m128 enter = clip.lower, exit = clip.upper;
  for (int axis = 0; axis < 3; ++axis) {
    const __m128 a = _mm_add_ps(clip.planeLow[axis], _mm_mul_ps(low[axis], clip.step[axis]));
    const __m128 b = _mm_add_ps(clip.planeHigh[axis], _mm_mul_ps(high[axis], clip.step[axis]));
    enter = _mm_max_ps(enter, _mm_min_ps(a, b));
    exit = _mm_min_ps(exit, _mm_max_ps(a, b));
  }
  _mm_storeu_ps(entries, enter);
  return unsigned(_mm_movemask_ps(_mm_cmple_ps(enter, exit)));
}

// Tests the triangles of packets[first, end) whose box the ray crosses,
// folding hits into `best`; with AnyHit, returns true at the first hit. The
// boxes first, 64 at a time and without branches, then the packets they
// pass, prefetched together so that their cache misses overlap. A closest-
// hit query skips a packet whose box the ray enters only beyond the best hit
// found so far (often one found in an earlier packet of the voxel): the box
// test's own argument (uniform_grid.cpp) puts the computed entry before the
// hit of any triangle of the packet that the voxel must test, so such a
// triangle cannot win. The lanes packetCandidates keeps go to
// intersectTriangle itself, once per primitive (the mailbox), which alone
// decides hits.
template <bool AnyHit, uint32_t Slots>
inline bool testPackets(const TrianglePacket* packets, const PacketBoxes4* boxes, uint32_t first, uint32_t end,
                        const PacketBoxClip& clip, Mailbox<Slots>& mailbox, const PacketRay& packetRay,
                        const WatertightRay& frame, const Ray& ray, Hit& best) {
  const uint32_t endBlock = (end + 3) / 4;
  for (uint32_t block = first / 4; block < endBlock; block += 16) {
    const uint32_t blocks = std::min(endBlock - block, 16u), base = 4 * block;
    uint64_t crossed = 0;
    float entries[64];
    for (uint32_t k = 0; k < blocks; ++k)
      crossed |= uint64_t(crossedPacketBoxes(boxes[block + k], clip, entries + 4 * k)) << (4 * k);
    // Only the voxel's own packets (its first and last blocks may hold others).
    if (first > base) crossed &= ~uint64_t(0) << (first - base);
    if (end - base < 64) crossed &= (uint64_t(1) << (end - base)) - 1;
    for (uint64_t bits = crossed; bits != 0; bits &= bits - 1) {
      const char* const start = reinterpret_cast<const char*>(packets + base + std::countr_zero(bits));
      // Spelled out: GCC keeps a loop over an initializer list.
      __builtin_prefetch(start);
      __builtin_prefetch(start + 64);
      __builtin_prefetch(start + 128);
      __builtin_prefetch(start + sizeof(TrianglePacket) - 1);
    }
    for (; crossed != 0; crossed &= crossed - 1) {
      if constexpr (!AnyHit) {
        if (entries[std::countr_zero(crossed)] > best.t) continue;
      }
      const TrianglePacket& packet = packets[base + std::countr_zero(crossed)];
      for (unsigned mask = packetCandidates<AnyHit>(packet, packetRay, best.t); mask != 0;) {
        const int lane = __builtin_ctz(mask);
        mask &= mask - 1;
        const uint32_t primitive = packet.primitive[lane];
        if (!mailbox.firstVisit(primitive)) continue;
        const Vec3 v0{packet.v[0][0][lane], packet.v[0][1][lane], packet.v[0][2][lane]};
        const Vec3 v1{packet.v[1][0][lane], packet.v[1][1][lane], packet.v[1][2][lane]};
        const Vec3 v2{packet.v[2][0][lane], packet.v[2][1][lane], packet.v[2][2][lane]};
        float t, u, v;
        if (!intersectTriangle(frame, ray, v0, v1, v2, t, u, v)) continue;
        if constexpr (AnyHit) return true;
        if (closerThan(t, primitive, best)) best = Hit{t, primitive, u, v};
      }
    }
  }
  return false;
}

// Tests the triangles references[first, end) not tested yet, folding hits
// into `best`. With AnyHit, returns true at the first hit.
template <bool AnyHit, uint32_t Slots>
inline bool testReferences(const uint32_t* references, uint32_t first, uint32_t end, Mailbox<Slots>& mailbox,
                           const MeshView& mesh, const WatertightRay& frame, const Ray& ray, Hit& best) {
  for (uint32_t r = first; r < end; ++r) {
    const uint32_t primitive = references[r];
    if (!mailbox.firstVisit(primitive)) continue;
    Vec3 v0, v1, v2;
    mesh.triangle(primitive, v0, v1, v2);
    float t, u, v;
    if (!intersectTriangle(frame, ray, v0, v1, v2, t, u, v)) continue;
    if constexpr (AnyHit) return true;
    if (closerThan(t, primitive, best)) best = Hit{t, primitive, u, v};
  }
  return false;
}

}  // namespace portico::grid_traversal
