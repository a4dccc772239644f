// kd-tree traversal: iterative, front to back, with a small fixed stack
// (after Wald's thesis and pbrt), over the flat nodes of kd_node.h.
//
// Why the kd-tree returns exactly brute force's hit. The builders keep every
// point of a triangle X inside the closed box of some leaf that references X
// (kd_build.h). The watertight test is backward stable: the point
// origin + tX * direction of a hit it reports lies within a few float ulps of
// its distance to the ray origin from X (and so within eps = c * u * R of it,
// R being the largest distance from the origin to the root box, per axis).
// The traversal therefore treats every plane, the root box's faces included,
// as a slab of half-width margin = R / 2^18 + |origin| / 2^20, far above eps
// plus the rounding of the traversal's own arithmetic (whose terms are at
// most a few ulps of R and of the origin's coordinates, the latter from
// precomputing margin - origin once per ray): the ray is in a child over the whole
// parameter range where it is within `margin` of the child's box. Every
// reported hit's parameter tX thus falls in the visited range of a leaf
// referencing X. The ranges of the children overlap; each stacked node keeps
// the lower end of its own range, and is skipped only when the best hit so
// far is strictly nearer (best.t < its start): so a triangle at the same t
// with a smaller id is still found (closerThan decides), and nothing skipped
// can beat the hit returned.
//
// Zero direction components give infinite reciprocals: the products below
// are then +-infinity on the correct side of each slab, and NaN only for an
// origin exactly on a slab face, where every test is written so that NaN
// means "visit". Rays with a non-zero component whose reciprocal overflows
// (a denormal) fall back to testing every triangle.
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstring>

#include "common/accel/kd_tree.h"
#include "common/accel/traversal_margin.h"
#include "common/accel/triangle_intersect.h"

namespace portico {

namespace {

constexpr int kStackSize = 64;
static_assert(kStackSize > kKdMaxDepthLimit);

// Per-ray constants of one axis.
struct RayAxis {
  float planeNear;  // split + planeNear = split - origin + margin, toward the far side
  float planeFar;   // split + planeFar = split - origin - margin
  float inverse;    // of the direction
  uint32_t nearIsAbove;  // the near child is the one above the plane (direction's sign bit set)
};

// Clips [tNear, tFar] to the root box grown by the margin, and sets the
// axes' plane offsets. False when nothing of the ray is left.
[[gnu::always_inline]] inline bool clipToRootBox(const float origin[3], const float direction[3],
                                                 const Bounds3& box, float margin, RayAxis axes[3], float& tNear,
                                                 float& tFar) {
  for (int axis = 0; axis < 3; ++axis) {
    const float signedMargin = std::copysign(margin, direction[axis]);
    axes[axis].planeNear = signedMargin - origin[axis];
    axes[axis].planeFar = -signedMargin - origin[axis];
    const bool nearIsAbove = axes[axis].nearIsAbove;
    const float nearFace = nearIsAbove ? box.hi[axis] : box.lo[axis];
    const float farFace = nearIsAbove ? box.lo[axis] : box.hi[axis];
    const float tEnter = ((nearFace - origin[axis]) - signedMargin) * axes[axis].inverse;
    const float tExit = ((farFace - origin[axis]) + signedMargin) * axes[axis].inverse;
    if (tEnter > tNear) tNear = tEnter;  // NaN (origin on a face, direction 0): no limit
    if (tExit < tFar) tFar = tExit;
  }
  return tNear <= tFar;
}

}  // namespace

template <bool AnyHit>
bool KdTree::testEveryTriangle(const Ray& ray, Hit& best) const {
  const WatertightRay frame(ray.direction);
  for (uint32_t primitive = 0; primitive < uint32_t(mesh_.triangleCount); ++primitive) {
    Vec3 v0, v1, v2;
    mesh_.triangle(primitive, v0, v1, v2);
    if (!isFinite(v0) || !isFinite(v1) || !isFinite(v2)) continue;  // not in the tree either
    float t, u, v;
    if (!intersectTriangle(frame, ray, v0, v1, v2, t, u, v)) continue;
    if constexpr (AnyHit) return true;
    if (closerThan(t, primitive, best)) best = Hit{t, primitive, u, v};
  }
  return best.found();
}

// Flattened: the triangle test is inlined into the loop.
template <bool AnyHit>
[[gnu::flatten]] bool KdTree::traverse(const Ray& ray, Hit& best) const {
  if (tree_.nodes.empty() || !hasFiniteOriginAndDirection(ray) || !(ray.tMin < ray.tMax)) return false;
  const float origin[3] = {ray.origin.x, ray.origin.y, ray.origin.z};
  const float direction[3] = {ray.direction.x, ray.direction.y, ray.direction.z};
  if (direction[0] == 0.0f && direction[1] == 0.0f && direction[2] == 0.0f) return false;

  // Per-ray constants, per axis, and the margin: 2^-16 of the reach R, plus
  // 16 ulps of the origin's largest coordinate for the rounding of
  // planeNear and planeFar.
  RayAxis axes[3];
  for (int axis = 0; axis < 3; ++axis) {
    axes[axis].inverse = 1.0f / direction[axis];
    if (direction[axis] != 0.0f && !std::isfinite(axes[axis].inverse))
      return testEveryTriangle<AnyHit>(ray, best);
    axes[axis].nearIsAbove = std::signbit(direction[axis]) ? 1 : 0;
  }
  const float margin = traversalMargin(tree_.bounds, origin);
  float tNear = ray.tMin, tFar = ray.tMax;
  if (!clipToRootBox(origin, direction, tree_.bounds, margin, axes, tNear, tFar)) return false;

  // Nodes are handled as 64-bit words (payload low, bits high), so that
  // they stay in integer registers.
  const KdNode* const nodes = tree_.nodes.data();
  const auto load = [nodes](uint32_t index) {
    uint64_t word;
    std::memcpy(&word, nodes + index, sizeof(word));
    return word;
  };
  const auto bitsOf = [](uint64_t word) { return uint32_t(word >> 32); };
  const auto payloadOf = [](uint64_t word) { return uint32_t(word); };
  static_assert(offsetof(KdNode, payload) == 0 && offsetof(KdNode, bits) == 4 &&
                std::endian::native == std::endian::little);

  const WatertightRay frame(ray.direction);
  const uint32_t* const primitives = tree_.primitives.data();
  struct Pending {
    uint64_t node;
    float tNear, tFar;
  };
  Pending stack[kStackSize];
  int pending = 0;
  uint64_t node = load(0);

  for (;;) {
    // Descend to a leaf, stacking the far children the ray also reaches.
    // Both children are loaded (they share a cache line) while the plane is
    // being intersected, so the next step does not wait for its load.
    while ((bitsOf(node) & 3) != KdNode::kLeafTag) {
      const RayAxis& axis = axes[bitsOf(node) & 3];
      const uint32_t firstChild = bitsOf(node) >> 2;
      const uint64_t below = load(firstChild), above = load(firstChild + 1);
      // Both children's own children, one step ahead of the choice (for a
      // leaf, a harmless address near the start of the nodes). Prefetching
      // a leaf's triangles there instead measured slower (the selects).
      __builtin_prefetch(nodes + (bitsOf(below) >> 2));
      __builtin_prefetch(nodes + (bitsOf(above) >> 2));
      const float split = std::bit_cast<float>(payloadOf(node));
      // Where the ray leaves the near child's (grown) box, and enters the far one's.
      const float tLeaveNear = (split + axis.planeNear) * axis.inverse;
      const float tEnterFar = (split + axis.planeFar) * axis.inverse;
      const uint64_t nearNode = axis.nearIsAbove ? above : below;
      const uint64_t farNode = axis.nearIsAbove ? below : above;
      // tEnterFar <= tLeaveNear, so with tNear <= tFar at least one is
      // visited. Branch-free: which child comes next is a coin toss the
      // branch predictor would lose; the far child is written to the stack
      // every time and kept only when both are visited.
      const bool visitNear = !(tLeaveNear < tNear);
      const bool visitFar = !(tEnterFar > tFar);
      const float farNear = tEnterFar > tNear ? tEnterFar : tNear;
      stack[pending] = {farNode, farNear, tFar};
      pending += int(visitNear & visitFar);
      node = visitNear ? nearNode : farNode;
      const float nearFar = tLeaveNear < tFar ? tLeaveNear : tFar;
      tNear = visitNear ? tNear : farNear;
      tFar = visitNear ? nearFar : tFar;
    }

    // Test the leaf's triangles.
    const uint32_t count = bitsOf(node) >> 2;
    const auto test = [&](uint32_t primitive) {
      Vec3 v0, v1, v2;
      mesh_.triangle(primitive, v0, v1, v2);
      float t, u, v;
      if (!intersectTriangle(frame, ray, v0, v1, v2, t, u, v)) return false;
      if (closerThan(t, primitive, best)) best = Hit{t, primitive, u, v};
      return true;
    };
    if (count == 1) {
      if (test(payloadOf(node)) && AnyHit) return true;
    } else {
      const uint32_t* const list = primitives + payloadOf(node);
      for (uint32_t i = 0; i < count; ++i)
        if (test(list[i]) && AnyHit) return true;
    }

    // The next stacked node that may hold a hit at best.t or nearer.
    for (;;) {
      if (pending == 0) return best.found();
      const Pending& next = stack[--pending];
      if (best.t < next.tNear) continue;
      node = next.node;
      tNear = next.tNear;
      tFar = next.tFar < best.t ? next.tFar : best.t;
      break;
    }
  }
}

Hit KdTree::intersect(const Ray& ray) const {
  Hit best;
  traverse<false>(ray, best);
  return best;
}

bool KdTree::occluded(const Ray& ray) const {
  Hit unused;
  return traverse<true>(ray, unused);
}

}  // namespace portico
