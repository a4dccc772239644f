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
// boxes are tested as slabs grown by margin = R / 2^18 + |origin| / 2^20
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

namespace {
// The largest of lanes 0-2 (lane 3 is zero: values are not negative).
inline float largestLane(__m128 v) {
  v = _mm_max_ps(v, _mm_shuffle_ps(v, v, _MM_SHUFFLE(2, 3, 0, 1)));
  v = _mm_max_ps(v, _mm_shuffle_ps(v, v, _MM_SHUFFLE(1, 0, 3, 2)));
  return _mm_cvtss_f32(v);
}
}  // namespace

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
  if (tree_.nodes.empty() || !(ray.tMin < ray.tMax)) return false;
  // Per-ray constants, three axes to a register (lane 3 unused: zero
  // origin, direction 1). Loads of four floats from the ray's origin and
  // direction (the fourth is the next member) and from the root's corners.
  const __m128 axes = _mm_castsi128_ps(_mm_setr_epi32(-1, -1, -1, 0));
  const __m128 absolute = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff));
  const __m128 origin = _mm_and_ps(_mm_loadu_ps(&ray.origin.x), axes);
  const __m128 direction = _mm_and_ps(_mm_loadu_ps(&ray.direction.x), axes);
  // Finite: x - x is 0, not NaN.
  if (_mm_movemask_ps(_mm_cmpunord_ps(_mm_sub_ps(origin, origin), _mm_sub_ps(direction, direction))) != 0)
    return false;
  const __m128 zero = _mm_cmpeq_ps(direction, _mm_setzero_ps());
  if (_mm_movemask_ps(zero) == 0xf) return false;   // a zero direction

  // The three reciprocals in one division (the same correctly rounded
  // quotients as three scalar ones); each must be normal, or infinite from
  // a zero component.
  const __m128 inverses = _mm_div_ps(_mm_set1_ps(1.0f), _mm_or_ps(direction, _mm_andnot_ps(axes, _mm_set1_ps(1.0f))));
  const __m128 magnitudes = _mm_and_ps(inverses, absolute);
  const __m128 normal = _mm_and_ps(_mm_cmpge_ps(magnitudes, _mm_set1_ps(std::numeric_limits<float>::min())),
                                   _mm_cmple_ps(magnitudes, _mm_set1_ps(std::numeric_limits<float>::max())));
  const __m128 usable = _mm_or_ps(zero, normal);
  if (_mm_movemask_ps(usable) != 0xf) return testEveryPacket<AnyHit>(ray, best);

  // The margin (traversal_margin.h, the same value), toward the near side
  // of each slab: origin + margin for the near bounds, - margin for the far.
  const __m128 low = _mm_loadu_ps(&tree_.bounds.lo.x);                 // lo.x lo.y lo.z hi.x
  const __m128 highShifted = _mm_loadu_ps(&tree_.bounds.lo.z);         // lo.z hi.x hi.y hi.z
  const __m128 high = _mm_shuffle_ps(highShifted, highShifted, _MM_SHUFFLE(0, 3, 2, 1));
  const __m128 reach = _mm_and_ps(_mm_max_ps(_mm_and_ps(_mm_sub_ps(low, origin), absolute),
                                             _mm_and_ps(_mm_sub_ps(high, origin), absolute)), axes);
  const float margin = traversalMargin(largestLane(reach), largestLane(_mm_and_ps(origin, absolute)));
  const __m128 signs = _mm_andnot_ps(absolute, direction);
  const __m128 towardNear = _mm_xor_ps(_mm_set1_ps(margin), signs);   // lowers the near bound's t
  BvhSlabs slabs;
  _mm_storeu_ps(slabs.nearOrigin, _mm_add_ps(origin, towardNear));
  _mm_storeu_ps(slabs.farOrigin, _mm_sub_ps(origin, towardNear));
  _mm_storeu_ps(slabs.inverse, inverses);
  const int negative = _mm_movemask_ps(signs);
  for (int axis = 0; axis < 3; ++axis) slabs.nearSide[axis] = (negative >> axis) & 1;

  // The watertight test's frame, its quotients in one division beside the
  // reciprocals': Sz = 1 / d[kz] is a reciprocal already.
  WatertightRay frame;
  frame.chooseAxes(ray.direction);
  const float d[3] = {ray.direction.x, ray.direction.y, ray.direction.z};
  alignas(16) float shear[4];
  _mm_store_ps(shear, _mm_div_ps(_mm_setr_ps(d[frame.kx], d[frame.ky], 1.0f, 1.0f),
                                 _mm_setr_ps(d[frame.kz], d[frame.kz], 1.0f, 1.0f)));
  frame.Sx = shear[0];
  frame.Sy = shear[1];
  frame.Sz = slabs.inverse[frame.kz];

  if constexpr (Width == 8) {
    // The AVX2 test's origin' x inverse must be finite on every axis whose
    // inverse is (see bvh_traverse_avx2.cpp).
    const __m128 nearScaled = _mm_mul_ps(_mm_loadu_ps(slabs.nearOrigin), inverses);
    const __m128 farScaled = _mm_mul_ps(_mm_loadu_ps(slabs.farOrigin), inverses);
    const __m128 infinite = _mm_set1_ps(kInfinity);
    const __m128 overflow = _mm_andnot_ps(zero, _mm_or_ps(_mm_cmpnlt_ps(_mm_and_ps(nearScaled, absolute), infinite),
                                                          _mm_cmpnlt_ps(_mm_and_ps(farScaled, absolute), infinite)));
    if (bvhAvx2InUse() && _mm_movemask_ps(overflow) == 0) {
      _mm_storeu_ps(slabs.nearScaled, nearScaled);
      _mm_storeu_ps(slabs.farScaled, farScaled);
      return traverseBvh8Avx2<AnyHit>(tree_, ray, slabs, frame, best);
    }
  }
  return traverseBvh<Width, AnyHit, SseBoxes>(tree_, ray, slabs, frame, best);
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
