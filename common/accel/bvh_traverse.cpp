// `bvh` traversal: per node, the boxes of all children against the ray at
// once (SSE, four children per instruction; AVX2, eight, for 8-wide trees
// where the processor has it: bvh_traverse_avx2.cpp), the children the ray enters
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
// origin's coordinates; the AVX2 test's fused multiply-add rounds within
// the same bounds, bvh_traverse_avx2.cpp): so the computed entry into every box on X's path is
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

#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "common/accel/bvh.h"
#include "common/accel/bvh_traverse_avx2.h"
#include "common/accel/bvh_traverse_loop.h"
#include "common/accel/traversal_margin.h"

namespace portico {

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

template <int Width>
template <bool AnyHit>
bool WideBvh<Width>::traverse(const Ray& ray, Hit& best) const {
  if (tree_.nodes.empty() || !hasFiniteOriginAndDirection(ray) || !(ray.tMin < ray.tMax)) return false;
  const float origin[3] = {ray.origin.x, ray.origin.y, ray.origin.z};
  const float direction[3] = {ray.direction.x, ray.direction.y, ray.direction.z};
  if (direction[0] == 0.0f && direction[1] == 0.0f && direction[2] == 0.0f) return false;

  // Per-ray constants: reciprocals, near sides, and the margin.
  // The three reciprocals in one division (the same correctly rounded
  // quotients as three scalar ones); each must be normal, or infinite from
  // a zero component.
  BvhSlabs slabs;
  const __m128 directions = _mm_setr_ps(direction[0], direction[1], direction[2], 1.0f);
  const __m128 inverses = _mm_div_ps(_mm_set1_ps(1.0f), directions);
  const __m128 magnitudes = _mm_andnot_ps(_mm_set1_ps(-0.0f), inverses);
  const __m128 usable = _mm_or_ps(_mm_cmpeq_ps(directions, _mm_setzero_ps()),
                                  _mm_and_ps(_mm_cmpge_ps(magnitudes, _mm_set1_ps(std::numeric_limits<float>::min())),
                                             _mm_cmple_ps(magnitudes, _mm_set1_ps(std::numeric_limits<float>::max()))));
  if (_mm_movemask_ps(usable) != 0xf) return testEveryPacket<AnyHit>(ray, best);
  alignas(16) float inverse[4];
  _mm_store_ps(inverse, inverses);
  for (int axis = 0; axis < 3; ++axis) {
    slabs.inverse[axis] = inverse[axis];
    slabs.nearSide[axis] = std::signbit(direction[axis]) ? 1 : 0;
  }
  const float margin = traversalMargin(tree_.bounds, origin);
  for (int axis = 0; axis < 3; ++axis) {
    const float towardNear = slabs.nearSide[axis] ? -margin : margin;   // lowers the near bound's t
    slabs.nearOrigin[axis] = origin[axis] + towardNear;
    slabs.farOrigin[axis] = origin[axis] - towardNear;
  }
  if constexpr (Width == 8) {
    if (bvhAvx2InUse() && bvhAvx2Suits(slabs)) return traverseBvh8Avx2<AnyHit>(tree_, ray, slabs, best);
  }
  return traverseBvh<Width, AnyHit, SseBoxes>(tree_, ray, slabs, best);
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
