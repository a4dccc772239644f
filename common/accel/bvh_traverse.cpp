// `bvh` traversal: per node, the boxes of all children against the ray at
// once (SSE, four children per instruction), the children the ray enters
// visited nearest first, the others kept on a short explicit stack; per
// leaf, the 4-wide filter of the watertight test, then intersectTriangle on
// the lanes it keeps.
//
// Why the BVH returns exactly brute force's hit. Every triangle that can be
// hit is in exactly one leaf, whose box, and every ancestor's, holds the
// triangle's box. The watertight test is backward stable: the point
// origin + tX * direction of a hit it reports lies within a few float ulps
// of the ray origin's distance to X (so within eps = c * u * R of X, R being
// the largest distance from the origin to the root box, per axis). The
// boxes are tested as slabs grown by margin = R / 2^16 + |origin| / 2^20
// (traversal_margin.h), far above eps plus the rounding
// of the slab arithmetic (origin +- margin rounded once per ray, then one
// subtraction and one multiplication per plane: a few ulps of R and of the
// origin's coordinates): so the computed entry into every box on X's path is
// at most tX and its exit at least tX, and X's leaf is reached unless the
// search has a hit strictly nearer than that entry. A child is visited when
// its entry is <= the best hit so far (and a stacked one is skipped only
// when the best hit is strictly nearer than its entry), so a triangle at
// the same t with a smaller id is still tested; closerThan decides among
// them, as in brute force, whatever the order of the tests. The leaves'
// vertices are the mesh's, copied bit for bit, and the 4-wide filter drops
// only lanes intersectTriangle would reject or that cannot win
// (grid_traversal::packetCandidates).
//
// Zero direction components give infinite reciprocals: the products are
// then +-infinity on the correct side of each slab, and NaN only for an
// origin exactly on a grown face; the maxima and minima are written so that
// NaN leaves the running entry and exit as they were (the child is visited).
// Rays whose reciprocals overflow (a denormal component) or are denormal or
// zero (a component beyond 2^126) test every packet instead.
#include <emmintrin.h>

#include <bit>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "common/accel/bvh.h"
#include "common/accel/traversal_margin.h"
#include "common/accel/triangle_intersect.h"

namespace portico {

namespace {

// The ray as the box tests need it, per axis, broadcast to four lanes:
// t = (bound - origin') * inverse, with origin' = origin + margin toward the
// near side for the near bounds and away from it for the far bounds, the
// near bound being the low one when the direction is positive.
struct SlabRay {
  __m128 nearOrigin[3], farOrigin[3], inverse[3];
  int nearSide[3];   // 0: the low bounds are the near ones; 1: the high ones
};

// Where the ray enters each of four boxes (the latest entry over the axes
// and tStart), and which it crosses before tLimit (bit k: box k). Box k's
// bounds are box[axis][side][k], here given at an offset into the node.
template <int Width>
inline unsigned crossedBoxes4(const BvhNode<Width>& node, int offset, const SlabRay& ray, __m128 tStart,
                              __m128 tLimit, float* entries) {
  __m128 enter = tStart, exit = tLimit;
  for (int axis = 0; axis < 3; ++axis) {
    const __m128 nearBound = _mm_load_ps(node.box[axis][ray.nearSide[axis]] + offset);
    const __m128 farBound = _mm_load_ps(node.box[axis][1 - ray.nearSide[axis]] + offset);
    const __m128 tNear = _mm_mul_ps(_mm_sub_ps(nearBound, ray.nearOrigin[axis]), ray.inverse[axis]);
    const __m128 tFar = _mm_mul_ps(_mm_sub_ps(farBound, ray.farOrigin[axis]), ray.inverse[axis]);
    // NaN (an origin on a face of a slab the ray runs in) keeps the second operand.
    enter = _mm_max_ps(tNear, enter);
    exit = _mm_min_ps(tFar, exit);
  }
  _mm_storeu_ps(entries, enter);
  return unsigned(_mm_movemask_ps(_mm_cmple_ps(enter, exit)));
}

struct StackEntry {
  uint32_t child;
  float entry;
};

// Tests a leaf's packets, folding hits into best; with AnyHit, true at the
// first hit. A lane the 4-wide test keeps with no edge function zero is a
// hit of intersectTriangle with the lane's t, and u = V / det, v = W / det
// (the same divisions): its sign test and range check passed on the scalar
// test's own values; det is not zero (t would be infinite or NaN and fail
// the strict range check); the scalar test's exact check of T / det against
// [tMin, tMax] in double agrees with its check of the rounded t (rounding
// is monotone and the bounds are floats); and degenerate triangles are not
// in the tree. Lanes with a zero edge function go to intersectTriangle,
// which re-decides them in double.
template <bool AnyHit>
inline bool testLeaf(const grid_traversal::TrianglePacket* packets, uint32_t child,
                     const grid_traversal::PacketRay& packetRay, const WatertightRay& frame, const Ray& ray,
                     Hit& best) {
  const grid_traversal::TrianglePacket* packet = packets + bvh_child::firstPacket(child);
  const grid_traversal::TrianglePacket* const end = packet + bvh_child::packetCount(child);
  for (; packet != end; ++packet) {
    const grid_traversal::PacketLanes lanes = grid_traversal::packetLanes<AnyHit>(*packet, packetRay, best.t);
    unsigned candidates = grid_traversal::laneBits(lanes.candidate);
    if (candidates == 0) continue;
    if constexpr (AnyHit) {
      if (candidates & ~grid_traversal::laneBits(lanes.anyZero)) return true;
    }
    const unsigned doubtful = grid_traversal::laneBits(lanes.anyZero);
    for (; candidates != 0; candidates &= candidates - 1) {
      const int lane = std::countr_zero(candidates);
      const uint32_t primitive = packet->primitive[lane];
      Hit hit{lanes.t[lane], primitive, 0, 0};
      if (doubtful & (1u << lane)) {
        const Vec3 v0{packet->v[0][0][lane], packet->v[0][1][lane], packet->v[0][2][lane]};
        const Vec3 v1{packet->v[1][0][lane], packet->v[1][1][lane], packet->v[1][2][lane]};
        const Vec3 v2{packet->v[2][0][lane], packet->v[2][1][lane], packet->v[2][2][lane]};
        if (!intersectTriangle(frame, ray, v0, v1, v2, hit.t, hit.u, hit.v)) continue;
        if constexpr (AnyHit) return true;
      } else {
        if (!closerThan(hit.t, primitive, best)) continue;
        hit.u = lanes.V[lane] / lanes.det[lane];
        hit.v = lanes.W[lane] / lanes.det[lane];
      }
      if (closerThan(hit.t, primitive, best)) best = hit;
    }
  }
  return false;
}

}  // namespace

template <int Width>
WideBvh<Width>::WideBvh(const MeshView& mesh, std::string_view spec) {
  const auto start = std::chrono::steady_clock::now();
  tree_ = buildBvh<Width>(mesh);
  stats_.spec = std::string(spec);
  stats_.buildMs =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  stats_.nodes = tree_.nodes.size();
  stats_.leaves = tree_.leaves;
  stats_.triangleReferences = tree_.triangles;
  stats_.averageDepth = tree_.leaves ? tree_.depthSum / double(tree_.leaves) : 0.0;
  stats_.maxDepth = tree_.maxDepth;
  stats_.bytes = sizeof(*this) + tree_.nodes.capacity() * sizeof(BvhNode<Width>) +
                 tree_.packets.capacity() * sizeof(grid_traversal::TrianglePacket);
}

template <int Width>
template <bool AnyHit>
bool WideBvh<Width>::testEveryPacket(const Ray& ray, Hit& best) const {
  const WatertightRay frame(ray.direction);
  const grid_traversal::PacketRay packetRay(frame, ray);
  const uint32_t packets = uint32_t(tree_.packets.size());
  for (uint32_t first = 0; first < packets; first += bvh_child::kMaxPackets) {
    const uint32_t count = std::min(bvh_child::kMaxPackets, packets - first);
    if (testLeaf<AnyHit>(tree_.packets.data(), bvh_child::leaf(first, count), packetRay, frame, ray, best))
      return true;
  }
  return best.found();
}

// Flattened: the box and triangle tests are inlined into the loop.
template <int Width>
template <bool AnyHit>
[[gnu::flatten]] bool WideBvh<Width>::traverse(const Ray& ray, Hit& best) const {
  if (tree_.nodes.empty() || !hasFiniteOriginAndDirection(ray) || !(ray.tMin < ray.tMax)) return false;
  const float origin[3] = {ray.origin.x, ray.origin.y, ray.origin.z};
  const float direction[3] = {ray.direction.x, ray.direction.y, ray.direction.z};
  if (direction[0] == 0.0f && direction[1] == 0.0f && direction[2] == 0.0f) return false;

  // Per-ray constants: reciprocals, near sides, and the margin.
  float inverse[3];
  SlabRay slab;
  for (int axis = 0; axis < 3; ++axis) {
    inverse[axis] = 1.0f / direction[axis];
    if (direction[axis] != 0.0f && !std::isnormal(inverse[axis])) return testEveryPacket<AnyHit>(ray, best);
    slab.nearSide[axis] = std::signbit(direction[axis]) ? 1 : 0;
  }
  const float margin = traversalMargin(tree_.bounds, origin);
  for (int axis = 0; axis < 3; ++axis) {
    const float towardNear = slab.nearSide[axis] ? -margin : margin;   // lowers the near bound's t
    slab.nearOrigin[axis] = _mm_set1_ps(origin[axis] + towardNear);
    slab.farOrigin[axis] = _mm_set1_ps(origin[axis] - towardNear);
    slab.inverse[axis] = _mm_set1_ps(inverse[axis]);
  }

  const WatertightRay frame(ray.direction);
  const grid_traversal::PacketRay packetRay(frame, ray);
  const __m128 tStart = _mm_set1_ps(ray.tMin);
  const BvhNode<Width>* const nodes = tree_.nodes.data();
  const grid_traversal::TrianglePacket* const packets = tree_.packets.data();
  StackEntry stack[(Width - 1) * kBvhMaxDepth + 1];
  int pending = 0;
  uint32_t current = 0;   // the root

  for (;;) {
    // Down the nodes, nearest child first, stacking the others the ray enters.
    while (!bvh_child::isLeaf(current)) {
      const BvhNode<Width>& node = nodes[current];
      const float limit = best.t < ray.tMax ? best.t : ray.tMax;
      const __m128 tLimit = _mm_set1_ps(limit);
      float entries[Width];
      unsigned crossed = crossedBoxes4(node, 0, slab, tStart, tLimit, entries);
      if constexpr (Width == 8) crossed |= crossedBoxes4(node, 4, slab, tStart, tLimit, entries + 4) << 4;
      if (crossed == 0) goto nextStacked;
      // Every child entered is loaded soon (the nearest next, the others
      // when popped): start their cache misses now, side by side.
      for (unsigned bits = crossed; bits != 0; bits &= bits - 1) {
        const uint32_t child = node.child[std::countr_zero(bits)];
        const char* const address =
            bvh_child::isLeaf(child) ? reinterpret_cast<const char*>(packets + bvh_child::firstPacket(child))
                                     : reinterpret_cast<const char*>(nodes + child);
        __builtin_prefetch(address);
        __builtin_prefetch(address + 64);
        __builtin_prefetch(address + 128);
      }
      if ((crossed & (crossed - 1)) == 0) {
        current = node.child[std::countr_zero(crossed)];
        continue;
      }
      // Two or more: sorted farthest first onto the stack; the nearest is next.
      StackEntry* const first = stack + pending;
      for (; crossed != 0; crossed &= crossed - 1) {
        const int k = std::countr_zero(crossed);
        const StackEntry entry{node.child[k], entries[k]};
        StackEntry* slot = stack + pending++;
        while (slot != first && slot[-1].entry < entry.entry) {
          *slot = slot[-1];
          --slot;
        }
        *slot = entry;
      }
      current = stack[--pending].child;
    }

    if (testLeaf<AnyHit>(packets, current, packetRay, frame, ray, best) && AnyHit) return true;

  nextStacked:
    // The next stacked child that may hold a hit at best.t or nearer.
    for (;;) {
      if (pending == 0) return best.found();
      const StackEntry& next = stack[--pending];
      if (!AnyHit && best.t < next.entry) continue;
      current = next.child;
      break;
    }
  }
}

template <int Width>
Hit WideBvh<Width>::intersect(const Ray& ray) const {
  Hit best;
  traverse<false>(ray, best);
  return best;
}

template <int Width>
bool WideBvh<Width>::occluded(const Ray& ray) const {
  Hit unused;
  return traverse<true>(ray, unused);
}

template class WideBvh<4>;
template class WideBvh<8>;

BvhOptions readBvhOptions(AcceleratorParameters& parameters) {
  BvhOptions options;
  options.width = parameters.integer("width", options.width, 1, 1 << 20);
  if (options.width != 4 && options.width != 8)
    parameters.fail("parameter width must be 4 or 8 (got " + std::to_string(options.width) + ")");
  return options;
}

std::unique_ptr<Accelerator> makeBvh(const MeshView& mesh, const BvhOptions& options, std::string_view spec) {
  if (options.width == 8) return std::make_unique<WideBvh<8>>(mesh, spec);
  return std::make_unique<WideBvh<4>>(mesh, spec);
}

}  // namespace portico
