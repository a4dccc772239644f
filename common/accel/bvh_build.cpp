// `bvh` build: binned SAH top-down (Wald, "On fast construction of SAH-based
// bounding volume hierarchies", 2007) straight into wide nodes.
//
// One 32-byte reference per triangle (its box, and its id in the box's
// spare lane) in one array, partitioned in place: a node's triangles are a
// contiguous range of it. A node starts as one child holding its whole
// range; the child of largest surface area is split by the best of 32
// binned SAH planes per axis (16 below 1024 references, 8 below 256, 4
// below 16; centroids binned; ranges of 8192 references or more bin every
// k-th, 4096 to 8191 of them), until the node has Width children or none is
// worth splitting. Costs count triangles in packets of four, as the leaves
// test them (Embree's block size), so a range of at most four triangles is
// one packet test and always a leaf, and one of at most eight becomes a
// leaf unless a split is predicted cheaper (in 8-wide trees, whose AVX2
// traversal tests two packets at once, always a leaf, and one of at most
// sixteen a leaf unless a split is predicted cheaper in two-packet tests).
// Triangles of a large share of the root's area (a room's floor, ceiling
// and walls) become leaves of the root (separateLarge). A range whose
// centroids all fall in one bin, or one deeper than kBvhForcedMedianDepth,
// is cut at its median instead. A range binned in full knows its sides'
// boxes and counts from the bins, so its partition only moves references
// (partitionByCount); a sampled one measures its sides' boxes while
// partitioning. Either way the sides' centroid boxes are bounded, not
// measured (boundCentroids). The leaves' packets are written once the
// tree is built, into one array of the exact size. O(n log n): each level
// bins and partitions each triangle of the levels' ranges a bounded number
// of times.
#include <emmintrin.h>
#include <immintrin.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <utility>
#include <vector>

#include "common/accel/bvh_build.h"
#include "common/accel/bvh_node.h"
#include "common/accel/triangle_intersect.h"

namespace portico {

namespace {


// Bins per axis: 32 for ranges of kFineBinning references or more, where a
// better plane pays for the longer sweep many times over, 16 below, 8
// below kCoarseBinning and 4 below kTinyBinning, where clearing and
// sweeping the bins outweighs binning the few references (8 bins up to 255
// rather than 31 and 4 below 16: builds ~10 % faster for a tree's SAH cost
// 0.1-0.2 % higher).
constexpr int kFineBins = 32;
constexpr int kBins = 16;
constexpr uint32_t kFineBinning = 1024;
constexpr int kCoarseBins = 8;
constexpr uint32_t kCoarseBinning = 256;
constexpr int kTinyBins = 4;
constexpr uint32_t kTinyBinning = 16;
// Ranges of at least this many references are binned into two sets of bins.
constexpr uint32_t kTwoBinSets = 256;
// Ranges of twice this many references or more bin every k-th, this many
// to twice as many in all: the best plane moves little, and the top levels
// cost little more than their partition.
constexpr uint32_t kSampledReferences = 4096;
constexpr uint32_t kPacketSize = 4;
constexpr uint32_t kAlwaysLeaf = 4;      // at most one packet: a leaf
// 8-wide trees, traced with AVX2, test a leaf's packets two at a time
// (testLeaf8): two packets cost about one, so up to eight triangles are a leaf.
template <int Width>
constexpr uint32_t kAlwaysLeafOf = Width == 8 ? 2 * kAlwaysLeaf : kAlwaysLeaf;
constexpr uint32_t kMaxLeaf = 8;         // at most two: a leaf unless a split is cheaper
// In 8-wide trees a range of up to four packets is a leaf unless a split is
// cheaper, its cost counted in the two-packet tests of testLeaf8.
template <int Width>
constexpr uint32_t kMaxLeafOf = Width == 8 ? 4 * kPacketSize : kMaxLeaf;
// SAH costs, in units of one packet test: one wide node's box test.
constexpr float kTraversalCost = 1.0f;
// Triangles whose box's half area is at least 1 / kLargeShare of the
// root's (a room's floor, ceiling and walls) become leaves of the root.
constexpr float kLargeShare = 64;

// A triangle's box (lanes 0-2) with its primitive id in lane 3 of lo.
struct alignas(32) PrimitiveReference {
  __m128 lo, hi;
  uint32_t primitive() const {
    uint32_t id;
    std::memcpy(&id, reinterpret_cast<const char*>(&lo) + 12, 4);
    return id;
  }
};

// Half the surface area of the box (lanes 0-2).
inline float halfArea(__m128 lo, __m128 hi) {
  alignas(16) float d[4];
  _mm_store_ps(d, _mm_sub_ps(hi, lo));
  return d[0] * d[1] + d[1] * d[2] + d[2] * d[0];
}

inline uint32_t packets(uint32_t triangles) { return (triangles + kPacketSize - 1) / kPacketSize; }

// A contiguous range of references, with the box of their triangles and the
// box of their centroids (taken as lo + hi: twice the centre, which bins alike).
struct Range {
  uint32_t begin = 0, end = 0;
  __m128 lo, hi, centroidLo, centroidHi;
  bool leaf = false;
  uint32_t count() const { return end - begin; }
};

// The bins of the three axes: the box of the references in each bin, and
// their counts side by side (count[bin][axis], lane 3 unused), so that the
// SAH sweep takes the three axes in the lanes of one SSE register.
struct BinBox {
  __m128 lo, hi;
};

template <int kBins>
struct BinSet {
  BinBox box[3][kBins];
  alignas(16) int32_t count[kBins][4];

  void clear() {
    const __m128 infinity = _mm_set1_ps(kInfinity), minusInfinity = _mm_set1_ps(-kInfinity);
    for (int axis = 0; axis < 3; ++axis)
      for (int b = 0; b < kBins; ++b) box[axis][b] = {infinity, minusInfinity};
    std::memset(count, 0, sizeof(count));
  }
  // Adds a reference to its bin of each axis. The bins' byte offsets come
  // from the SIMD bin indices by shifts and adds in the lanes (one register
  // move per axis and array, no scalar address arithmetic).
  // The byte offsets in box and in count of a reference's bins (lanes 0-2: axes).
  static void offsetsOf(__m128i bins, __m128i& boxOffset, __m128i& countOffset) {
    static_assert(sizeof(BinBox) == 32 && sizeof(count[0]) == 16);
    boxOffset = _mm_add_epi32(_mm_slli_epi32(bins, 5),
                              _mm_setr_epi32(0, kBins * sizeof(BinBox), 2 * kBins * sizeof(BinBox), 0));
    countOffset = _mm_add_epi32(_mm_slli_epi32(bins, 4), _mm_setr_epi32(0, 4, 8, 0));
  }
  void add(__m128i bins, __m128 referenceLo, __m128 referenceHi) {
    __m128i boxOffset, countOffset;
    offsetsOf(bins, boxOffset, countOffset);
    char* const boxes = reinterpret_cast<char*>(box);
    char* const counts = reinterpret_cast<char*>(count);
    const auto extend = [&](uint32_t boxAt, uint32_t countAt) {
      BinBox& bin = *reinterpret_cast<BinBox*>(boxes + boxAt);
      bin.lo = _mm_min_ps(bin.lo, referenceLo);
      bin.hi = _mm_max_ps(bin.hi, referenceHi);
      ++*reinterpret_cast<int32_t*>(counts + countAt);
    };
    extend(uint32_t(_mm_cvtsi128_si32(boxOffset)), uint32_t(_mm_cvtsi128_si32(countOffset)));
    extend(uint32_t(_mm_cvtsi128_si32(_mm_shuffle_epi32(boxOffset, 1))),
           uint32_t(_mm_cvtsi128_si32(_mm_shuffle_epi32(countOffset, 1))));
    extend(uint32_t(_mm_cvtsi128_si32(_mm_shuffle_epi32(boxOffset, 2))),
           uint32_t(_mm_cvtsi128_si32(_mm_shuffle_epi32(countOffset, 2))));
  }
  void merge(const BinSet& other) {
    for (int axis = 0; axis < 3; ++axis)
      for (int b = 0; b < kBins; ++b) {
        box[axis][b].lo = _mm_min_ps(box[axis][b].lo, other.box[axis][b].lo);
        box[axis][b].hi = _mm_max_ps(box[axis][b].hi, other.box[axis][b].hi);
      }
    // Whole rows (lane 3 is 0 in both), as the sweep loads them.
    for (int b = 0; b < kBins; ++b) {
      __m128i* row = reinterpret_cast<__m128i*>(count[b]);
      _mm_store_si128(row, _mm_add_epi32(_mm_load_si128(row), _mm_load_si128(reinterpret_cast<const __m128i*>(other.count[b]))));
    }
  }
};

// Half the surface areas of three boxes, one per lane: box k is (lo[k],
// hi[k]) with its axes in lanes 0-2. The same products and sums as halfArea.
inline __m128 halfAreas3(const __m128 (&lo)[3], const __m128 (&hi)[3]) {
  __m128 x = _mm_sub_ps(hi[0], lo[0]), y = _mm_sub_ps(hi[1], lo[1]), z = _mm_sub_ps(hi[2], lo[2]);
  __m128 w = _mm_setzero_ps();
  _MM_TRANSPOSE4_PS(x, y, z, w);   // x: the three boxes' x extents, and so on
  return _mm_add_ps(_mm_add_ps(_mm_mul_ps(x, y), _mm_mul_ps(y, z)), _mm_mul_ps(z, x));
}

// Packets of four for counts in lanes, as floats.
inline __m128 packets4(__m128i counts) {
  return _mm_cvtepi32_ps(_mm_srli_epi32(_mm_add_epi32(counts, _mm_set1_epi32(kPacketSize - 1)), 2));
}

// How a range's centroids map to bins: bin = (c - base) * scale, per axis.
struct Binning {
  __m128 base, scale;
  int binCount;
  // The three axes' scales in one division: bins x 0.99999 / extent where
  // the extent is positive (lanes 0-2), else 0.
  Binning(const Range& range, int bins) : base(range.centroidLo), binCount(bins) {
    const __m128 extent = _mm_sub_ps(range.centroidHi, range.centroidLo);
    const __m128 positive = _mm_and_ps(_mm_cmpgt_ps(extent, _mm_setzero_ps()),
                                       _mm_castsi128_ps(_mm_setr_epi32(-1, -1, -1, 0)));
    scale = _mm_and_ps(positive, _mm_div_ps(_mm_set1_ps(float(bins) * 0.99999f), extent));
  }
  // The bins of a centroid along the three axes (lane 3 unused), clamped to
  // [0, bins - 1] before truncation (rounding may stray by one at either
  // end): the same bins as clamping after it.
  __m128i bins(__m128 centroid) const {
    const __m128 x = _mm_mul_ps(_mm_sub_ps(centroid, base), scale);
    return _mm_cvttps_epi32(_mm_min_ps(_mm_max_ps(x, _mm_setzero_ps()), _mm_set1_ps(float(binCount - 1))));
  }
};

// Bins the references begin, begin + stride, ... of the array (alternate
// ones into odd when twoSets), merged into bins at the end.
template <int kBins>
void binReferences(BinSet<kBins>& bins, BinSet<kBins>& odd, bool twoSets, const Binning& binning,
                   const PrimitiveReference* references, uint32_t begin, uint32_t end, uint32_t stride) {
  bins.clear();
  if (twoSets) odd.clear();
  const auto add = [&binning](BinSet<kBins>& set, const PrimitiveReference& reference)
                       __attribute__((always_inline)) {
    set.add(binning.bins(_mm_add_ps(reference.lo, reference.hi)), reference.lo, reference.hi);
  };
  uint32_t i = begin;
  for (; twoSets && i + stride < end; i += 2 * stride) {
    add(bins, references[i]);
    add(odd, references[i + stride]);
  }
  for (; i < end; i += stride) add(bins, references[i]);
  if (twoSets) bins.merge(odd);
}

// binReferences with AVX, where the processor has it (chosen at run time).
const bool kAvxSupported = __builtin_cpu_supports("avx");
std::atomic<bool> avxBinning{kAvxSupported};

}  // namespace
}  // namespace portico

// Only the binning loop below is compiled for AVX: everything it calls is
// defined above, as baseline code.
#pragma GCC push_options
#pragma GCC target("avx")

namespace portico {
namespace {

// The same bins as binReferences, each bin's box updated by one 8-lane
// minimum: the bin holds (lo, -hi) while binning, so the minimum of -hi is
// minus the maximum of hi, exactly.
template <int kBins>
void binReferencesAvx(BinSet<kBins>& bins, BinSet<kBins>& odd, bool twoSets, const Binning& rangeBinning,
                      const PrimitiveReference* references, uint32_t begin, uint32_t end, uint32_t stride) {
  const Binning binning = rangeBinning;   // a copy the bins' stores cannot alias
  static_assert(sizeof(BinBox) == sizeof(__m256) && sizeof(PrimitiveReference) == sizeof(__m256));
  const __m256 signOfHi = _mm256_setr_ps(0, 0, 0, 0, -0.0f, -0.0f, -0.0f, -0.0f);
  // Adding -0 leaves every float as it is (-0 too); lane 3 counts one more.
  const __m256 one = _mm256_setr_ps(-0.0f, -0.0f, -0.0f, 1, -0.0f, -0.0f, -0.0f, -0.0f);
  const __m256 infinity = _mm256_set1_ps(kInfinity);
  // Lane 3 of a bin counts its references, as a float (exact below 2^24,
  // and a range bins at most 2 x kSampledReferences of them): the count
  // rides in the box's own load and store.
  const auto clear = [&](BinSet<kBins>& set) {
    const __m256 empty = _mm256_setr_ps(kInfinity, kInfinity, kInfinity, 0, kInfinity, kInfinity, kInfinity, kInfinity);
    for (int axis = 0; axis < 3; ++axis)
      for (int b = 0; b < kBins; ++b) _mm256_store_ps(reinterpret_cast<float*>(&set.box[axis][b]), empty);
  };
  // Each bin's row of counts (the three axes' lanes 3) is written as one
  // vector, which the sweep's load of it takes straight from the store.
  const auto restoreHi = [&](BinSet<kBins>& set) {
    for (int b = 0; b < kBins; ++b) {
      const __m128 x = _mm_load_ps(reinterpret_cast<const float*>(&set.box[0][b]));
      const __m128 y = _mm_load_ps(reinterpret_cast<const float*>(&set.box[1][b]));
      const __m128 z = _mm_load_ps(reinterpret_cast<const float*>(&set.box[2][b]));
      const __m128 counts = _mm_shuffle_ps(_mm_unpackhi_ps(x, y), _mm_unpackhi_ps(z, _mm_setzero_ps()),
                                           _MM_SHUFFLE(3, 2, 3, 2));
      _mm_store_si128(reinterpret_cast<__m128i*>(set.count[b]), _mm_cvttps_epi32(counts));
    }
    for (int axis = 0; axis < 3; ++axis)
      for (int b = 0; b < kBins; ++b) {
        float* box = reinterpret_cast<float*>(&set.box[axis][b]);
        _mm256_store_ps(box, _mm256_xor_ps(_mm256_load_ps(box), signOfHi));
      }
  };
  const auto add = [&](BinSet<kBins>& set, const PrimitiveReference& reference) __attribute__((always_inline)) {
    // (lo, -hi), with +infinity in lane 3 (the id's), which the minimum then
    // leaves to the bin's count.
    const __m256 box =
        _mm256_blend_ps(_mm256_xor_ps(_mm256_load_ps(reinterpret_cast<const float*>(&reference)), signOfHi), infinity, 0x08);
    __m128i boxOffset, countOffset;
    BinSet<kBins>::offsetsOf(binning.bins(_mm_add_ps(reference.lo, reference.hi)), boxOffset, countOffset);
    char* const boxes = reinterpret_cast<char*>(set.box);
    const auto extend = [&](uint32_t boxAt) {
      float* bin = reinterpret_cast<float*>(boxes + boxAt);
      _mm256_store_ps(bin, _mm256_add_ps(_mm256_min_ps(_mm256_load_ps(bin), box), one));
    };
    extend(uint32_t(_mm_cvtsi128_si32(boxOffset)));
    extend(uint32_t(_mm_extract_epi32(boxOffset, 1)));
    extend(uint32_t(_mm_extract_epi32(boxOffset, 2)));
  };
  clear(bins);
  if (twoSets) clear(odd);
  uint32_t i = begin;
  // Sampled references lie a stride apart, where the processor's own
  // prefetch does not look: they are asked for kAhead samples early.
  constexpr uint32_t kAhead = 16;
  const bool prefetch = stride > 1;
  for (; twoSets && i + stride < end; i += 2 * stride) {
    if (prefetch && i + (kAhead + 1) * stride < end) {
      _mm_prefetch(reinterpret_cast<const char*>(references + i + kAhead * stride), _MM_HINT_T0);
      _mm_prefetch(reinterpret_cast<const char*>(references + i + (kAhead + 1) * stride), _MM_HINT_T0);
    }
    add(bins, references[i]);
    add(odd, references[i + stride]);
  }
  for (; i < end; i += stride) add(bins, references[i]);
  restoreHi(bins);
  if (twoSets) {
    restoreHi(odd);
    bins.merge(odd);
  }
}

}  // namespace
}  // namespace portico

#pragma GCC pop_options

namespace portico {
namespace {

struct Split {
  int axis = -1;
  int bins = kBins;     // per axis
  int bin = 0;          // references with bin < this go left
  float cost = 0;       // SAH, in packet tests per unit of the parent's half area
  float base = 0, scale = 0;   // the binning along the split's axis (Binning)
  // When every reference was binned: the two sides' boxes and the left
  // side's count, exact, so the partition need not measure them.
  bool exact = false;
  uint32_t leftCount = 0;
  __m128 leftLo, leftHi, rightLo, rightHi;
};

// The one-axis side test of a split: bins(centroid)[axis] < split.bin,
// without the other axes. For x >= 0 truncation gives a bin below split.bin
// exactly when x < split.bin (and clamping to the last bin keeps
// x >= split.bin on the right); x < 0 is bin 0 either way.
struct SideTest {
  float base, scale, limit;
  int axis;
  explicit SideTest(const Split& split)
      : base(split.base), scale(split.scale), limit(float(split.bin)), axis(split.axis) {}
  bool left(const PrimitiveReference& reference) const {
    const float* lo = reinterpret_cast<const float*>(&reference.lo);
    const float* hi = reinterpret_cast<const float*>(&reference.hi);
    return (lo[axis] + hi[axis] - base) * scale < limit;
  }
};

// A build's scratch: the references, and the leaves' triangle ids and
// ranges (Builder::writeLeaf). Each thread keeps its own from one build to
// the next: a fresh page costs a fault and the kernel's zeroing, ~10 % of a
// 500k-triangle build when all are fresh, and a worker builds cell after
// cell. Kept only after builds of up to kKeptReferences triangles (about
// 72 MiB of it used); a larger build's scratch is freed with it. The
// references are uninitialised, and from 2 MiB on whole huge pages
// (bvh_memory): one fault per 2 MiB when they are fresh.
constexpr size_t kKeptReferences = size_t(2) << 20;
struct BuildScratch {
  PrimitiveReference* references = nullptr;
  size_t capacity = 0;   // references
  std::vector<uint32_t> leafPrimitives;
  std::vector<std::pair<uint32_t, uint32_t>> leafRanges;

  ~BuildScratch() { release(); }
  static bool onHugePages(size_t bytes) { return bytes >= bvh_memory::kHugePage; }
  PrimitiveReference* referencesFor(size_t count) {
    if (count <= capacity) return references;
    release();
    size_t bytes = std::max<size_t>(count, 1) * sizeof(PrimitiveReference);
    if (onHugePages(bytes)) {
      bytes = bvh_memory::hugePageBytes(bytes);   // whole huge pages, all ours
      references = static_cast<PrimitiveReference*>(bvh_memory::allocateHugePages(bytes));
    } else {
      references = static_cast<PrimitiveReference*>(::operator new(bytes, std::align_val_t{32}));
    }
    capacity = bytes / sizeof(PrimitiveReference);
    return references;
  }
  // After a build: what a small build left stays for the next.
  void finish() {
    leafPrimitives.clear();
    leafRanges.clear();
    if (capacity > kKeptReferences) release();
  }
  void release() {
    const size_t bytes = capacity * sizeof(PrimitiveReference);
    if (references && onHugePages(bytes))
      bvh_memory::freeHugePages(references, bytes);
    else if (references)
      ::operator delete(references, std::align_val_t{32});
    references = nullptr;
    capacity = 0;
    std::vector<uint32_t>().swap(leafPrimitives);
    std::vector<std::pair<uint32_t, uint32_t>>().swap(leafRanges);
  }
};
thread_local BuildScratch buildScratch;

template <int Width>
class Builder {
 public:
  Builder(const MeshView& mesh, BvhData<Width>& out)
      : mesh_(mesh), out_(out), scratch_(buildScratch), leafPrimitives_(scratch_.leafPrimitives),
        leafRanges_(scratch_.leafRanges) {}
  ~Builder() { scratch_.finish(); }

  void build() {
    Range root = gatherReferences();
    if (root.count() == 0) return;
    // About what the furnished halls need (leaves of ~6 triangles in ~2 packets).
    out_.nodes.reserve(size_t(root.count()) / (2 * Width) + 2);
    // At most one leaf a triangle; pages reserved and never written cost nothing.
    leafRanges_.reserve(root.count());
    leafPrimitives_.reserve(root.count());
    root.leaf = false;   // the root is always a node, even over one leaf
    alignas(16) float lo[4], hi[4];
    _mm_store_ps(lo, root.lo);
    _mm_store_ps(hi, root.hi);
    out_.bounds = Bounds3({lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]});
    out_.triangles = root.count();
    Range largeLeaves[Width];
    const int largeLeafCount = separateLarge(root, largeLeaves);
    buildNode(root, 1, largeLeaves, largeLeafCount);
    writePackets();
  }

 private:
  // The corners of a reference's box, lo then hi.
  static std::array<float, 6> corners(const PrimitiveReference& reference) {
    alignas(16) float lo[4], hi[4];
    _mm_store_ps(lo, reference.lo);
    _mm_store_ps(hi, reference.hi);
    return {lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]};
  }

  // Moves the root's large triangles (kLargeShare) out of its range into
  // leaves of their own, those of one box together (a rectangle's two
  // triangles), four at most a leaf; returns how many leaves. Centroid
  // binning cannot place them: a floor's centroid lies mid-room, and the
  // subtree that took it would span the room, entered by every ray. As
  // leaves of the root, each flat box is entered only by the rays that reach
  // its plane inside it, and nearest first puts it after the nearer
  // furniture, which usually hides it. With more than Width - 2 such leaves
  // (too few slots left for the rest), none: the root's range stays whole.
  int separateLarge(Range& root, Range (&leaves)[Width]) {
    constexpr uint32_t kMostLarge = kPacketSize * (Width - 2);
    const float rootArea = halfArea(root.lo, root.hi);
    if (!(rootArea > 0)) return 0;
    // One pass: the others moved down in order (measured as they go), the
    // large ones aside. More than fit in the leaves: they are put back
    // into the slots already read past, the range the same set.
    PrimitiveReference* const references = references_;
    PrimitiveReference large[kMostLarge];
    uint32_t taken = 0, kept = root.begin;
    const __m128 infinity = _mm_set1_ps(kInfinity);
    __m128 lo = infinity, hi = _mm_set1_ps(-kInfinity), centroidLo = lo, centroidHi = hi;
    const auto putBack = [&] {
      std::copy(large, large + taken, references + kept);
      return 0;
    };
    for (uint32_t i = root.begin; i < root.end; ++i) {
      const PrimitiveReference reference = references[i];
      if (halfArea(reference.lo, reference.hi) * kLargeShare >= rootArea) {
        if (taken == kMostLarge) return putBack();
        large[taken++] = reference;
        continue;
      }
      references[kept++] = reference;
      lo = _mm_min_ps(lo, reference.lo);
      hi = _mm_max_ps(hi, reference.hi);
      const __m128 centroid = _mm_add_ps(reference.lo, reference.hi);
      centroidLo = _mm_min_ps(centroidLo, centroid);
      centroidHi = _mm_max_ps(centroidHi, centroid);
    }
    if (taken == 0) return 0;
    std::stable_sort(large, large + taken, [](const PrimitiveReference& a, const PrimitiveReference& b) {
      return corners(a) < corners(b);
    });
    if (kept == root.begin) return putBack();   // nothing but large ones
    int count = 0;
    for (uint32_t start = 0; start < taken;) {
      uint32_t end = start + 1;
      while (end < taken && end - start < kPacketSize && corners(large[end]) == corners(large[start])) ++end;
      if (count == Width - 2) return putBack();
      Range& leaf = leaves[count++];
      leaf.begin = kept + start, leaf.end = kept + end;
      leaf.leaf = true;
      start = end;
    }
    putBack();
    for (int k = 0; k < count; ++k) measure(leaves[k]);
    root.end = kept;
    root.lo = lo, root.hi = hi, root.centroidLo = centroidLo, root.centroidHi = centroidHi;
    return count;
  }

  // A vertex in lanes 0-2 of a register; lane 3 holds the next float of
  // the positions, read only where the mesh promises one (padding, or a
  // next vertex).
  __m128 loadVertex(uint32_t vertex) const {
    const float* p = mesh_.positions + 3 * size_t(vertex);
    return vertex + 1 < mesh_.vertexCount || mesh_.positionsPaddingFloats > 0 ? _mm_loadu_ps(p)
                                                                               : _mm_setr_ps(p[0], p[1], p[2], 0);
  }

  // isDegenerateTriangle of the vertices in lanes 0-2, from the registers:
  // the same double differences, products and comparisons, two at a time.
  static bool isDegenerate(__m128 v0, __m128 v1, __m128 v2) {
    const __m128d xy0 = _mm_cvtps_pd(v0), z0 = _mm_cvtps_pd(_mm_movehl_ps(v0, v0));
    const __m128d xy1 = _mm_sub_pd(_mm_cvtps_pd(v1), xy0), z1 = _mm_sub_sd(_mm_cvtps_pd(_mm_movehl_ps(v1, v1)), z0);
    const __m128d xy2 = _mm_sub_pd(_mm_cvtps_pd(v2), xy0), z2 = _mm_sub_sd(_mm_cvtps_pd(_mm_movehl_ps(v2, v2)), z0);
    // a = v1 - v0, b = v2 - v0: (ay bz, az bx) against (az by, ax bz), and ax by against ay bx.
    const __m128d ayz = _mm_unpacklo_pd(_mm_unpackhi_pd(xy1, xy1), z1), bzx = _mm_unpacklo_pd(z2, xy2);
    const __m128d azx = _mm_unpacklo_pd(z1, xy1), byz = _mm_unpacklo_pd(_mm_unpackhi_pd(xy2, xy2), z2);
    const __m128d axyByx = _mm_mul_pd(xy1, _mm_shuffle_pd(xy2, xy2, 1));   // (ax by, ay bx)
    const int first = _mm_movemask_pd(_mm_cmpeq_pd(_mm_mul_pd(ayz, bzx), _mm_mul_pd(azx, byz)));
    const int last = _mm_movemask_pd(_mm_cmpeq_sd(axyByx, _mm_unpackhi_pd(axyByx, axyByx)));
    return first == 3 && (last & 1);
  }

  // References to every finite, non-degenerate triangle, and their range.
  Range gatherReferences() {
    references_ = scratch_.referencesFor(mesh_.triangleCount);
    uint32_t count = 0;
    __m128 lo = _mm_set1_ps(kInfinity), hi = _mm_set1_ps(-kInfinity);
    __m128 centroidLo = lo, centroidHi = hi;
    const __m128 infinity = _mm_set1_ps(kInfinity), absolute = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff));
    const __m128 xyz = _mm_castsi128_ps(_mm_setr_epi32(-1, -1, -1, 0));
    // The vertices are read through the indices, in no order the processor
    // foresees: those of the triangle kVerticesAhead on are asked for now.
    constexpr uint32_t kVerticesAhead = 16;
    for (uint32_t primitive = 0; primitive < mesh_.triangleCount; ++primitive) {
      const uint32_t* corner = mesh_.indices + 3 * size_t(primitive);
      if (primitive + kVerticesAhead < mesh_.triangleCount)
        for (int vertex = 0; vertex < 3; ++vertex)
          _mm_prefetch(reinterpret_cast<const char*>(mesh_.positions + 3 * size_t(corner[3 * kVerticesAhead + vertex])),
                       _MM_HINT_T0);
      const __m128 a = loadVertex(corner[0]), b = loadVertex(corner[1]), c = loadVertex(corner[2]);
      // Finite: |v| < infinity, false for NaN too.
      const __m128 finite = _mm_and_ps(_mm_and_ps(_mm_cmplt_ps(_mm_and_ps(a, absolute), infinity),
                                                  _mm_cmplt_ps(_mm_and_ps(b, absolute), infinity)),
                                       _mm_cmplt_ps(_mm_and_ps(c, absolute), infinity));
      if ((_mm_movemask_ps(finite) & 7) != 7) continue;
      if (isDegenerate(a, b, c)) continue;
      PrimitiveReference& reference = references_[count++];
      // The id joins lo in a register: stored apart, its 4 bytes would keep
      // the next load of lo from being forwarded from the store.
      const __m128 id = _mm_castsi128_ps(_mm_slli_si128(_mm_cvtsi32_si128(int(primitive)), 12));
      reference.lo = _mm_or_ps(_mm_and_ps(_mm_min_ps(_mm_min_ps(a, b), c), xyz), id);
      reference.hi = _mm_and_ps(_mm_max_ps(_mm_max_ps(a, b), c), xyz);
      lo = _mm_min_ps(lo, reference.lo);
      hi = _mm_max_ps(hi, reference.hi);
      const __m128 centroid = _mm_add_ps(reference.lo, reference.hi);
      centroidLo = _mm_min_ps(centroidLo, centroid);
      centroidHi = _mm_max_ps(centroidHi, centroid);
    }
    Range range;
    range.begin = 0;
    range.end = count;
    range.lo = lo, range.hi = hi, range.centroidLo = centroidLo, range.centroidHi = centroidHi;
    return range;
  }

  // The best binned SAH split of the range (axis -1: every centroid in one bin).
  Split findSplit(const Range& range) const {
    if (range.count() >= kFineBinning) return findSplitWith<kFineBins>(range);
    if (range.count() < kTinyBinning) return findSplitWith<kTinyBins>(range);
    return range.count() >= kCoarseBinning ? findSplitWith<kBins>(range) : findSplitWith<kCoarseBins>(range);
  }

  template <int kBins>
  Split findSplitWith(const Range& range) const {
    const Binning binning(range, kBins);
    // Two sets of bins, for alternate references, merged after: consecutive
    // references (neighbours in space) often fall in the same bins, and one
    // set would chain every update on the one before.
    const bool twoSets = range.count() >= kTwoBinSets;
    const uint32_t stride = std::max(1u, range.count() / kSampledReferences);
    BinSet<kBins> bins, odd;
    if (avxBinning.load(std::memory_order_relaxed))
      binReferencesAvx(bins, odd, twoSets, binning, references_, range.begin, range.end, stride);
    else
      binReferences(bins, odd, twoSets, binning, references_, range.begin, range.end, stride);
    Split best = sweep(bins);
    best.bins = kBins;
    if (best.axis >= 0) {
      alignas(16) float base[4], scale[4];
      _mm_store_ps(base, binning.base);
      _mm_store_ps(scale, binning.scale);
      best.base = base[best.axis], best.scale = scale[best.axis];
    }
    if (stride == 1 && best.axis >= 0) sidesOf(bins, best);
    return best;
  }

  // The exact boxes and left count of the split's two sides, from bins that
  // hold every reference of the range.
  template <int kBins>
  static void sidesOf(const BinSet<kBins>& bins, Split& split) {
    const __m128 infinity = _mm_set1_ps(kInfinity), minusInfinity = _mm_set1_ps(-kInfinity);
    __m128 lo[2] = {infinity, infinity}, hi[2] = {minusInfinity, minusInfinity};
    uint32_t leftCount = 0;
    for (int b = 0; b < kBins; ++b) {
      const int side = b < split.bin ? 0 : 1;
      lo[side] = _mm_min_ps(lo[side], bins.box[split.axis][b].lo);
      hi[side] = _mm_max_ps(hi[side], bins.box[split.axis][b].hi);
      if (side == 0) leftCount += uint32_t(bins.count[b][split.axis]);
    }
    split.exact = true;
    split.leftCount = leftCount;
    split.leftLo = lo[0], split.leftHi = hi[0], split.rightLo = lo[1], split.rightHi = hi[1];
  }

  // The cheapest plane of the binned range, the three axes at once (one per
  // lane): right to left, the boxes and counts of bins b..kBins - 1; then
  // left to right, those of bins 0..b - 1 and the cost of each plane. Ties
  // go to the lower axis, then the lower bin.
  template <int kBins>
  static Split sweep(const BinSet<kBins>& bins) {
    const __m128 infinity = _mm_set1_ps(kInfinity), minusInfinity = _mm_set1_ps(-kInfinity);
    __m128 rightArea[kBins];
    __m128i rightCount[kBins];
    __m128 lo[3] = {infinity, infinity, infinity}, hi[3] = {minusInfinity, minusInfinity, minusInfinity};
    __m128i count = _mm_setzero_si128();
    for (int b = kBins - 1; b > 0; --b) {
      for (int axis = 0; axis < 3; ++axis) {
        lo[axis] = _mm_min_ps(lo[axis], bins.box[axis][b].lo);
        hi[axis] = _mm_max_ps(hi[axis], bins.box[axis][b].hi);
      }
      count = _mm_add_epi32(count, _mm_load_si128(reinterpret_cast<const __m128i*>(bins.count[b])));
      rightCount[b] = count;
      rightArea[b] = halfAreas3(lo, hi);
    }
    __m128 bestCost = infinity;
    __m128i bestBin = _mm_setzero_si128();
    for (int axis = 0; axis < 3; ++axis) lo[axis] = infinity, hi[axis] = minusInfinity;
    count = _mm_setzero_si128();
    const __m128i zero = _mm_setzero_si128();
    for (int b = 1; b < kBins; ++b) {
      for (int axis = 0; axis < 3; ++axis) {
        lo[axis] = _mm_min_ps(lo[axis], bins.box[axis][b - 1].lo);
        hi[axis] = _mm_max_ps(hi[axis], bins.box[axis][b - 1].hi);
      }
      count = _mm_add_epi32(count, _mm_load_si128(reinterpret_cast<const __m128i*>(bins.count[b - 1])));
      const __m128 cost = _mm_add_ps(_mm_mul_ps(halfAreas3(lo, hi), packets4(count)),
                                     _mm_mul_ps(rightArea[b], packets4(rightCount[b])));
      const __m128i empty = _mm_or_si128(_mm_cmpeq_epi32(count, zero), _mm_cmpeq_epi32(rightCount[b], zero));
      const __m128i better = _mm_andnot_si128(empty, _mm_castps_si128(_mm_cmplt_ps(cost, bestCost)));
      bestCost = _mm_or_ps(_mm_and_ps(_mm_castsi128_ps(better), cost), _mm_andnot_ps(_mm_castsi128_ps(better), bestCost));
      bestBin = _mm_or_si128(_mm_and_si128(better, _mm_set1_epi32(b)), _mm_andnot_si128(better, bestBin));
    }
    alignas(16) float costs[4];
    alignas(16) int32_t binOf[4];
    _mm_store_ps(costs, bestCost);
    _mm_store_si128(reinterpret_cast<__m128i*>(binOf), bestBin);
    Split best;
    best.cost = kInfinity;
    for (int axis = 0; axis < 3; ++axis)
      if (costs[axis] < best.cost) best.cost = costs[axis], best.axis = axis, best.bin = binOf[axis];
    return best;
  }

  // Partitions the range by the split, measuring the two sides' boxes (the
  // split's own come from sampled bins in large ranges); their centroid
  // boxes are bounded (boundCentroids), as partitionByCount's are.
  void partition(const Range& range, const Split& split, Range& left, Range& right) {
    const __m128 infinity = _mm_set1_ps(kInfinity), minusInfinity = _mm_set1_ps(-kInfinity);
    __m128 leftLo = infinity, leftHi = minusInfinity, rightLo = infinity, rightHi = minusInfinity;
    const SideTest test(split);
    uint32_t i = range.begin, j = range.end;
    while (i < j) {
      if (test.left(references_[i])) {
        leftLo = _mm_min_ps(leftLo, references_[i].lo);
        leftHi = _mm_max_ps(leftHi, references_[i].hi);
        ++i;
      } else {
        rightLo = _mm_min_ps(rightLo, references_[i].lo);
        rightHi = _mm_max_ps(rightHi, references_[i].hi);
        std::swap(references_[i], references_[--j]);
      }
    }
    left.begin = range.begin, left.end = i;
    right.begin = i, right.end = range.end;
    left.lo = leftLo, left.hi = leftHi;
    right.lo = rightLo, right.hi = rightHi;
    boundCentroids(range, split, left, right);
  }

  // Cuts the range at its median along the longest axis of its centroids;
  // for ranges binning cannot separate, and below the forced-median depth.
  void splitAtMedian(const Range& range, Range& left, Range& right) {
    alignas(16) float extent[4];
    _mm_store_ps(extent, _mm_sub_ps(range.centroidHi, range.centroidLo));
    const int axis = extent[0] >= extent[1] && extent[0] >= extent[2] ? 0 : (extent[1] >= extent[2] ? 1 : 2);
    const uint32_t middle = range.begin + range.count() / 2;
    const auto centre = [axis](const PrimitiveReference& r) {
      alignas(16) float c[4];
      _mm_store_ps(c, _mm_add_ps(r.lo, r.hi));
      return c[axis];
    };
    std::nth_element(references_ + range.begin, references_ + middle,
                     references_ + range.end,
                     [&](const PrimitiveReference& a, const PrimitiveReference& b) { return centre(a) < centre(b); });
    left.begin = range.begin, left.end = middle;
    right.begin = middle, right.end = range.end;
    measure(left);
    measure(right);
  }

  void measure(Range& range) const {
    __m128 lo = _mm_set1_ps(kInfinity), hi = _mm_set1_ps(-kInfinity), centroidLo = lo, centroidHi = hi;
    for (uint32_t i = range.begin; i < range.end; ++i) {
      lo = _mm_min_ps(lo, references_[i].lo);
      hi = _mm_max_ps(hi, references_[i].hi);
      const __m128 centroid = _mm_add_ps(references_[i].lo, references_[i].hi);
      centroidLo = _mm_min_ps(centroidLo, centroid);
      centroidHi = _mm_max_ps(centroidHi, centroid);
    }
    range.lo = lo, range.hi = hi, range.centroidLo = centroidLo, range.centroidHi = centroidHi;
  }

  // Splits the range in two; false when it should stay a leaf.
  bool split(const Range& range, int depth, Range& left, Range& right) {
    if (range.count() <= kAlwaysLeafOf<Width>) return false;
    if (depth >= kBvhForcedMedianDepth) {
      splitAtMedian(range, left, right);
      return true;
    }
    const Split best = findSplit(range);
    if (best.axis < 0) {
      if (range.count() <= kMaxLeafOf<Width>) return false;
      splitAtMedian(range, left, right);
      return true;
    }
    if (range.count() <= kMaxLeafOf<Width>) {
      // Leaf: its packet tests, every ray that reaches it. Split: a node's
      // box test and the children's packet tests, each for the fraction of
      // those rays its box takes. 8-wide trees test packets in pairs: their
      // costs count pairs (the split's, halved, rounds each side's down).
      const float area = halfArea(range.lo, range.hi);
      const float tests = Width == 8 ? float((packets(range.count()) + 1) / 2) : float(packets(range.count()));
      const float splitTests = Width == 8 ? 0.5f * best.cost : best.cost;
      if (tests * area <= splitTests + kTraversalCost * area) return false;
    }
    if (best.exact) partitionByCount(range, best, left, right);
    else partition(range, best, left, right);
    return true;
  }

  // Partitions the range by an exact split, whose sides' boxes and counts
  // the bins measured: the partition only moves references. Blocks of the
  // left part's misplaced references (those going right) and of the right
  // part's (going left) are listed without branches, then swapped in pairs
  // (Edelkamp and Weiss's BlockQuicksort): no branch on a reference's side.
  // The children's centroid boxes are bounded rather than measured: the
  // parent's, cut to twice their triangles' box.
  void partitionByCount(const Range& range, const Split& split, Range& left, Range& right) {
    const SideTest test(split);
    const uint32_t middle = range.begin + split.leftCount;
    constexpr uint32_t kBlock = 64;
    uint32_t leftMisplaced[kBlock], rightMisplaced[kBlock];
    uint32_t i = range.begin, j = middle;
    uint32_t leftListed = 0, leftDone = 0, rightListed = 0, rightDone = 0;
    PrimitiveReference* references = references_;
    for (;;) {
      if (leftDone == leftListed) {
        if (i == middle) break;
        leftListed = leftDone = 0;
        for (const uint32_t stop = std::min(i + kBlock, middle); i < stop; ++i) {
          leftMisplaced[leftListed] = i;
          leftListed += !test.left(references[i]);
        }
      }
      if (rightDone == rightListed) {
        if (j == range.end) break;
        rightListed = rightDone = 0;
        for (const uint32_t stop = std::min(j + kBlock, range.end); j < stop; ++j) {
          rightMisplaced[rightListed] = j;
          rightListed += test.left(references[j]);
        }
      }
      const uint32_t pairs = std::min(leftListed - leftDone, rightListed - rightDone);
      for (uint32_t k = 0; k < pairs; ++k)
        std::swap(references[leftMisplaced[leftDone + k]], references[rightMisplaced[rightDone + k]]);
      leftDone += pairs, rightDone += pairs;
    }
    left.begin = range.begin, left.end = middle;
    right.begin = middle, right.end = range.end;
    left.lo = split.leftLo, left.hi = split.leftHi;
    right.lo = split.rightLo, right.hi = split.rightHi;
    boundCentroids(range, split, left, right);
  }

  // The sides' centroid boxes, bounded rather than measured: the parent's,
  // cut to twice the side's box (a centroid, lo + hi, lies within it) and,
  // along the split axis, to the plane.
  static void boundCentroids(const Range& range, const Split& split, Range& left, Range& right) {
    const auto centroidBounds = [&range](Range& side) {
      side.centroidLo = _mm_max_ps(range.centroidLo, _mm_add_ps(side.lo, side.lo));
      side.centroidHi = _mm_min_ps(range.centroidHi, _mm_add_ps(side.hi, side.hi));
    };
    centroidBounds(left);
    centroidBounds(right);
    // And along the split axis, to the plane (widened by a little more than
    // the side test's rounding: a centroid just outside only loses resolution).
    alignas(16) float leftHi[4], rightLo[4], lo[4], hi[4];
    _mm_store_ps(leftHi, left.centroidHi);
    _mm_store_ps(rightLo, right.centroidLo);
    _mm_store_ps(lo, range.centroidLo);
    _mm_store_ps(hi, range.centroidHi);
    const int axis = split.axis;
    const float extent = hi[axis] - lo[axis];
    const float plane = lo[axis] + extent * (float(split.bin) / (float(split.bins) * 0.99999f));
    const float slack = 1e-5f * (extent + std::abs(plane));
    leftHi[axis] = std::min(leftHi[axis], plane + slack);
    rightLo[axis] = std::max(rightLo[axis], plane - slack);
    left.centroidHi = _mm_load_ps(leftHi);
    right.centroidLo = _mm_load_ps(rightLo);
  }

  // Writes the node for the range (and, depth first, its subtrees), with
  // the given leaves as its last children; returns its index.
  uint32_t buildNode(const Range& range, int depth, const Range* leaves = nullptr, int leafCount = 0) {
    Range children[Width];
    float areas[Width];   // the children's half areas, each taken once
    int count = 1;
    children[0] = range;
    areas[0] = halfArea(range.lo, range.hi);
    while (count < Width - leafCount) {
      int widest = -1;
      float widestArea = -1;
      for (int k = 0; k < count; ++k)
        if (!children[k].leaf && areas[k] > widestArea) widestArea = areas[k], widest = k;
      if (widest < 0) break;
      Range left, right;
      if (!split(children[widest], depth, left, right)) {
        children[widest].leaf = true;
        continue;
      }
      children[widest] = left;
      areas[widest] = halfArea(left.lo, left.hi);
      children[count] = right;
      areas[count++] = halfArea(right.lo, right.hi);
    }
    // Children the node had no slot left to split: small ones become leaves.
    for (int k = 0; k < count; ++k)
      if (children[k].count() <= kMaxLeafOf<Width>) children[k].leaf = true;
    for (int k = 0; k < leafCount; ++k) children[count++] = leaves[k];

    const uint32_t index = uint32_t(out_.nodes.size());
    out_.nodes.emplace_back();
    BvhNode<Width> node;
    for (int k = 0; k < Width; ++k) {
      alignas(16) float lo[4] = {kInfinity, kInfinity, kInfinity, 0}, hi[4] = {-kInfinity, -kInfinity, -kInfinity, 0};
      if (k < count) {
        _mm_store_ps(lo, children[k].lo);
        _mm_store_ps(hi, children[k].hi);
      }
      for (int axis = 0; axis < 3; ++axis) node.box[axis][0][k] = lo[axis], node.box[axis][1][k] = hi[axis];
      node.child[k] = 0;
    }
    for (int k = 0; k < count; ++k)
      node.child[k] = children[k].leaf ? writeLeaf(children[k], depth + 1) : buildNode(children[k], depth + 1);
    out_.nodes[index] = node;
    return index;
  }

  // Numbers the leaf's packets; writePackets fills them once the tree is
  // built and their count known (one exact allocation). The leaf's
  // triangle ids are copied now, while its references are in cache, into
  // one array in the leaves' order, which writePackets then reads straight
  // through.
  uint32_t writeLeaf(const Range& range, int depth) {
    const uint32_t first = packetCount_;
    const uint32_t count = packets(range.count());
    if (first + count - 1 > bvh_child::kMaxFirstPacket)
      throw std::length_error("bvh: more than 2^28 triangle packets");
    packetCount_ += count;
    const uint32_t start = uint32_t(leafPrimitives_.size());
    for (uint32_t r = range.begin; r < range.end; ++r) leafPrimitives_.push_back(references_[r].primitive());
    leafRanges_.push_back({start, start + range.count()});
    ++out_.leaves;
    out_.depthSum += depth;
    out_.maxDepth = std::max<uint32_t>(out_.maxDepth, uint32_t(depth));
    return bvh_child::leaf(first, count);
  }

  // The leaves' packets, in the order writeLeaf numbered them: each
  // vertex of the four triangles loaded as a row and transposed into the
  // packet's columns.
  void writePackets() {
    out_.packets.reserve(packetCount_);
    const size_t leaves = leafRanges_.size();
    // The mesh is read in the leaves' order, not the file's: its lines are
    // prefetched a few leaves ahead, the indices first, the vertices once
    // their indices have arrived.
    constexpr size_t kIndicesAhead = 4, kVerticesAhead = 2;
    for (size_t leaf = 0; leaf < leaves; ++leaf) {
      if (leaf + kIndicesAhead < leaves)
        for (uint32_t r = leafRanges_[leaf + kIndicesAhead].first; r < leafRanges_[leaf + kIndicesAhead].second; ++r)
          _mm_prefetch(reinterpret_cast<const char*>(mesh_.indices + 3 * size_t(leafPrimitives_[r])), _MM_HINT_T0);
      if (leaf + kVerticesAhead < leaves)
        for (uint32_t r = leafRanges_[leaf + kVerticesAhead].first; r < leafRanges_[leaf + kVerticesAhead].second; ++r) {
          const uint32_t* corner = mesh_.indices + 3 * size_t(leafPrimitives_[r]);
          for (int vertex = 0; vertex < 3; ++vertex)
            _mm_prefetch(reinterpret_cast<const char*>(mesh_.positions + 3 * size_t(corner[vertex])), _MM_HINT_T0);
        }
      const auto [begin, end] = leafRanges_[leaf];
      for (uint32_t start = begin; start < end; start += kPacketSize) {
        grid_traversal::TrianglePacket packet;
        __m128 rows[3][kPacketSize];
        for (uint32_t lane = 0; lane < kPacketSize; ++lane) {
          const uint32_t primitive = leafPrimitives_[std::min(start + lane, end - 1)];
          const uint32_t* corner = mesh_.indices + 3 * size_t(primitive);
          for (int vertex = 0; vertex < 3; ++vertex) rows[vertex][lane] = loadVertex(corner[vertex]);
          packet.primitive[lane] = primitive;
        }
        for (int vertex = 0; vertex < 3; ++vertex) {
          _MM_TRANSPOSE4_PS(rows[vertex][0], rows[vertex][1], rows[vertex][2], rows[vertex][3]);
          for (int axis = 0; axis < 3; ++axis) _mm_store_ps(packet.v[vertex][axis], rows[vertex][axis]);
        }
        out_.packets.push_back(packet);
      }
    }
  }

  const MeshView& mesh_;
  BvhData<Width>& out_;
  BuildScratch& scratch_;
  PrimitiveReference* references_ = nullptr;   // one per triangle of the mesh, the held ones first
  std::vector<uint32_t>& leafPrimitives_;   // the leaves' triangle ids, leaf after leaf
  std::vector<std::pair<uint32_t, uint32_t>>& leafRanges_;   // [begin, end) of each leaf's ids in leafPrimitives_
  uint32_t packetCount_ = 0;
};

}  // namespace

bool bvhAvxBinningInUse() { return avxBinning.load(std::memory_order_relaxed); }

void useBvhAvxBinning(bool use) { avxBinning.store(use && kAvxSupported, std::memory_order_relaxed); }

template <int Width>
BvhData<Width> buildBvh(const MeshView& mesh) {
  BvhData<Width> tree;
  Builder<Width>(mesh, tree).build();
  return tree;
}

template BvhData<4> buildBvh<4>(const MeshView& mesh);
template BvhData<8> buildBvh<8>(const MeshView& mesh);

}  // namespace portico
