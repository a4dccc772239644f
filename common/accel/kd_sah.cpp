// kd:sah: the surface area heuristic, built top-down in O(n log n) over
// references (a triangle and the bounds of its part inside the node).
//
// Each node's split is the SAH's best plane, found one of two ways:
//  - nodes of over kSmallNode (16) triangles: binned SAH (`bins` bins per
//    axis, default 32). One pass counts the references' start, end and
//    planar events per bin on the three axes at once (vector lanes); the
//    costs at the bin boundaries choose the axis and the best boundary;
//    a second pass collects that axis's events in the bins on either side
//    of it, which are sorted and swept exactly as Wald & Havran ("On
//    building fast kd-trees for ray tracing, and on doing that in
//    O(N log N)", 2006) sweep a whole node. So the plane is always on a
//    face of a triangle's box (a wall, a table top), where the exact SAH
//    puts it, and each node costs O(n) plus the sort of a few events.
//  - small nodes: the exact SAH, every box face a candidate, its counts
//    by comparing it with every box (O(n^2) for n <= 16, no sorting; a
//    box equal to the one before, a quad's second triangle, is merged
//    into it with a weight).
// Triangles lying in the plane go to the side where they cost less, so the
// axis-aligned walls, floors and furniture faces of a building end up in
// thin leaves of their own. A node stays a leaf when no split is cheaper;
// nodes of 1-2 triangles are first checked against a lower bound on every
// split's cost (splitCannotWin), which makes most of them leaves without
// the SAH. None of these shortcuts changes the tree: the same nodes,
// planes and leaves as the plain binned-plus-exact builder.
//
// Cost model: a leaf costs intersection * n; a split costs
//   traversal + intersection * (A_below * n_below + A_above * n_above) / A,
// times `empty` when one side of a plane strictly inside the node is empty.
//
// Straddling triangles are split by the plane and their parts' bounds cut
// to the reference's halves (perfect splits, splitTriangleToChildren); in
// nodes of at most kClipAbove (16) triangles, whose children are leaves or
// nearly, only the reference's box is cut.
//
// Memory: the references live in one arena used as a stack. A node's are
// at its top; its split writes above's in place and below's just past the
// node's range, so that the below child, built first, is the top of the
// stack, and the above child's are still there when its turn comes. No
// allocation and no copy per node.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <limits>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#include <xmmintrin.h>  // _mm_movemask_ps (SSE, baseline x86-64)

#include "common/accel/kd_build.h"

namespace portico {

namespace {

// Event types, in the order they sort at equal positions: the sweep must see
// a plane's ends before its planar triangles, and those before its starts.
constexpr uint32_t kEnd = 0, kPlanar = 1, kStart = 2;

// Maps floats (not NaN, no -0) to unsigned integers in the same order, and back.
inline uint32_t orderedBits(float position) {
  const uint32_t bits = std::bit_cast<uint32_t>(position);
  return (bits & 0x80000000u) ? ~bits : bits | 0x80000000u;
}
inline float fromOrderedBits(uint32_t ordered) {
  return std::bit_cast<float>((ordered & 0x80000000u) ? ordered & 0x7fffffffu : ~ordered);
}

// An event: where a triangle's box starts or ends along an axis, or where a
// flat box lies. Its value sorts by position, then type.
using Event = uint64_t;
inline Event makeEvent(float position, uint32_t type) {
  return uint64_t(orderedBits(position + 0.0f)) << 2 | type;  // + 0: no -0 events
}
inline uint32_t positionKey(Event event) { return uint32_t(event >> 2); }
inline uint32_t typeOf(Event event) { return uint32_t(event) & 3; }

// The SAH cost of planes along one axis of a node, in units of the
// intersection cost, scaled by the node's half area (the factor 2 cancels):
// leaf = A n; split = A traversal / intersection + A_below n_below + A_above n_above.
struct PlaneCost {
  float nodeLo, nodeHi;
  double perimeter, cross, splitBase, emptyBonus;
  uint32_t count;

  // Infinity when the split would leave a child equal to the node (a plane
  // on a face that moves nothing out).
  double operator()(float position, uint32_t below, uint32_t above) const {
    if ((position == nodeLo && above == count) || (position == nodeHi && below == count)) return kInfinity;
    const double belowArea = double(position - nodeLo) * perimeter + cross;
    const double aboveArea = double(nodeHi - position) * perimeter + cross;
    double cost = belowArea * below + aboveArea * above;
    if ((below == 0 || above == 0) && position > nodeLo && position < nodeHi) cost *= emptyBonus;
    return splitBase + cost;
  }
};

// The best split so far, and its cost.
struct BestSplit {
  double cost;
  std::optional<KdSplit> split;
};

// The sweep of Wald & Havran over sorted events of one axis. below counts
// the triangles reaching below the first event's position from before it,
// above those reaching above it (including the events' own triangles). At
// each plane p: `below` counts the triangles reaching below p, `above`
// those reaching above it, `planar` those lying in it; planar triangles go
// to the side where they cost less.
void sweep(std::span<const Event> events, uint32_t below, uint32_t above, const PlaneCost& cost, int axis,
           BestSplit& best) {
  for (size_t i = 0; i < events.size();) {
    const uint32_t key = positionKey(events[i]);
    uint32_t counts[3] = {0, 0, 0};  // ends, planars, starts at this position
    do ++counts[typeOf(events[i])];
    while (++i < events.size() && positionKey(events[i]) == key);
    const float position = fromOrderedBits(key);
    const uint32_t planar = counts[kPlanar];
    above -= planar + counts[kEnd];
    const double planarBelowCost = cost(position, below + planar, above);
    const double planarAboveCost = planar > 0 ? cost(position, below, above + planar) : kInfinity;
    if (planarBelowCost < best.cost || planarAboveCost < best.cost) {
      const bool planarBelow = planarBelowCost <= planarAboveCost;
      best.cost = planarBelow ? planarBelowCost : planarAboveCost;
      best.split = KdSplit{axis, position, planarBelow};
    }
    below += counts[kStart] + planar;
  }
}

// Four lanes at once (GCC and Clang vector extensions: SSE on x86-64). The
// lanes are the three axes (the fourth repeats the third and is ignored).
using Float4 = float __attribute__((vector_size(16)));
using Int4 = int32_t __attribute__((vector_size(16)));

// A triangle in a node: the bounds of its part inside the node, in arrays
// that an axis indexes and that load as vectors (32 bytes: a reference is
// copied as two vectors).
struct alignas(16) Reference {
  float lo[3];
  uint32_t primitive;
  float hi[3];
  uint32_t unused = 0;

  static Reference of(const Bounds3& box, uint32_t primitive) {
    return {{box.lo.x, box.lo.y, box.lo.z}, primitive, {box.hi.x, box.hi.y, box.hi.z}};
  }
  Bounds3 bounds() const { return Bounds3({lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}); }
  Float4 lo4() const { return load(offsetof(Reference, lo)); }
  Float4 hi4() const { return load(offsetof(Reference, hi)); }

 private:
  // The three floats at offset, and the third again (not the neighbour).
  Float4 load(size_t offset) const {
    Float4 v;
    std::memcpy(&v, reinterpret_cast<const char*>(this) + offset, sizeof(v));
    return __builtin_shufflevector(v, v, 0, 1, 2, 2);
  }
};
static_assert(sizeof(Reference) == 32 && offsetof(Reference, hi) == 16);

// A node's box, in arrays that an axis indexes.
struct Box {
  float lo[3], hi[3];

  Box below(int axis, float position) const {
    Box box = *this;
    box.hi[axis] = position;
    return box;
  }
  Box above(int axis, float position) const {
    Box box = *this;
    box.lo[axis] = position;
    return box;
  }
};

// A node's SAH (PlaneCost's terms) for the three axes in lanes. Lane 3 and
// flat axes (where every plane is a face) have NaN bounds: their costs are
// NaN, and never win.
struct NodeCost {
  Float4 lo, hi, perimeter, cross;
  double halfArea, splitBase, emptyBonus;
  uint32_t count;

  PlaneCost plane(int axis) const {
    return {lo[axis], hi[axis], double(perimeter[axis]), double(cross[axis]), splitBase, emptyBonus, count};
  }
};

// In nodes of at most this many triangles a straddling triangle's box is
// just cut at the plane: clipping the triangle costs more than it buys
// there, their subtrees being a few levels deep. 16 rather than 4 builds
// furnished halls 5-7 % faster (10 K-500 K triangles, interleaved A/B)
// with rays as fast; 64 makes the 500 K hall's photon rays 40 % slower.
constexpr uint32_t kClipAbove = 16;

// Nodes of at most this many triangles are first checked for a leaf that
// no split can beat (SahBuilder::splitCannotWin), before any SAH.
constexpr uint32_t kTinyNode = 2;

// Nodes of at most this many triangles are split by counting, not binning.
constexpr uint32_t kSmallNode = 16;

// The exact SAH of a small node: every face of every box is a candidate
// plane, and its counts below, above and in it come from comparing it with
// every box, on the three axes at once. O(n^2), but with no sorting, no
// branches and no per-node setup, the fastest way up to kSmallNode.
//
// The costs of PlaneCost, simplified: a plane on a face of the node never
// beats the leaf (its child equal to the node already costs as much), so
// it needs no test; and a plane leaves a side empty only at the lowest lo
// or the highest hi of the boxes, so the empty-space bonus goes to those
// two cuts, costed apart.
class SmallNodeSplitter {
 public:
  void findSplit(std::span<const Reference> references, const NodeCost& cost, BestSplit& best);

 private:
  // The boxes reaching below the plane at position, above it, and lying in it.
  struct Counts {
    Int4 below, above, planar;
  };
  // For the planes at the two faces of box (lo, hi) at once: each box is
  // loaded once for both. Weighted: each box counts as many times as the
  // references it stands for (an and more per count; only when some box
  // stands for several).
  template <bool Weighted>
  void countAround(uint32_t box, uint32_t count, Counts& atLo, Counts& atHi) const {
    const Float4 lo = lo_[box], hi = hi_[box];
    atLo = atHi = Counts{{}, {}, {}};
    for (uint32_t j = 0; j < count; ++j) {
      if constexpr (Weighted) {  // a true comparison is all ones: and it with the weight
        const Int4 weight = weight_[j];
        atLo.below += (lo_[j] < lo) & weight;
        atHi.below += (lo_[j] < hi) & weight;
        atLo.above += (hi_[j] > lo) & weight;
        atHi.above += (hi_[j] > hi) & weight;
        atLo.planar += (planar_[j] == lo) & weight;
        atHi.planar += (planar_[j] == hi) & weight;
      } else {  // a true comparison is -1
        atLo.below -= lo_[j] < lo;
        atHi.below -= lo_[j] < hi;
        atLo.above -= hi_[j] > lo;
        atHi.above -= hi_[j] > hi;
        atLo.planar -= planar_[j] == lo;
        atHi.planar -= planar_[j] == hi;
      }
    }
  }

  // Per distinct box (see findSplit): its lo and hi, its position on the
  // axes where it is flat (else NaN, equal to nothing), and how many
  // references have it.
  Float4 lo_[kSmallNode], hi_[kSmallNode], planar_[kSmallNode];
  Int4 weight_[kSmallNode];
  // Per candidate (lo then hi of each box), the costs (without the split's
  // own) with planar triangles below and above.
  Float4 planarBelowCost_[2 * kSmallNode], planarAboveCost_[2 * kSmallNode];
};

void SmallNodeSplitter::findSplit(std::span<const Reference> references, const NodeCost& cost, BestSplit& best) {
  const uint32_t count = uint32_t(references.size());
  constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
  Float4 lowest = Float4{} + kInfinity, highest = -lowest;
  // A box equal to the one before is not stored again but weighs more: its
  // faces are the same candidates with the same counts, and it adds to the
  // counts as its first copy does. Common: a quad's two triangles are
  // neighbours (the partitions keep the order) and share their box, about
  // a third of the boxes of small nodes in furnished halls. (Comparing with
  // every earlier box finds few more, at O(n^2).) The candidates keep their
  // order, so ties resolve as without merging.
  uint32_t boxes = 0;
  for (uint32_t j = 0; j < count; ++j) {
    const Float4 lo = references[j].lo4() + 0.0f, hi = references[j].hi4() + 0.0f;  // + 0: no -0
    lowest = lo < lowest ? lo : lowest;
    highest = hi > highest ? hi : highest;
    if (boxes > 0) {
      const Int4 same = (lo_[boxes - 1] == lo) & (hi_[boxes - 1] == hi);
      if (_mm_movemask_ps(reinterpret_cast<__m128>(same)) == 15) {  // lane 3 repeats lane 2
        weight_[boxes - 1] += 1;
        continue;
      }
    }
    lo_[boxes] = lo;
    hi_[boxes] = hi;
    planar_[boxes] = lo == hi ? lo : kNaN;
    weight_[boxes] = Int4{} + 1;
    ++boxes;
  }
  const Float4 nodeLo = cost.lo, nodeHi = cost.hi, perimeter = cost.perimeter, cross = cost.cross;
  const Float4 wholeArea = (nodeHi - nodeLo) * perimeter + cross + cross;  // below + above, for any plane
  const auto belowArea = [&](Float4 position) { return (position - nodeLo) * perimeter + cross; };
  const Float4 all = Float4{} + float(count);

  // Every candidate plane: the lowest cost per lane.
  Float4 cheapest = Float4{} + kInfinity;
  const auto record = [&](uint32_t k, Float4 position, const Counts& counts) {
    const Float4 areaBelow = belowArea(position), areaAbove = wholeArea - areaBelow;
    const Float4 planarBelowCost = areaBelow * __builtin_convertvector(counts.below + counts.planar, Float4) +
                                   areaAbove * __builtin_convertvector(counts.above, Float4);
    const Float4 planarAboveCost =
        planarBelowCost + (areaAbove - areaBelow) * __builtin_convertvector(counts.planar, Float4);
    planarBelowCost_[k] = planarBelowCost;
    planarAboveCost_[k] = planarAboveCost;
    cheapest = planarBelowCost < cheapest ? planarBelowCost : cheapest;
    cheapest = planarAboveCost < cheapest ? planarAboveCost : cheapest;
  };
  const bool weighted = boxes < count;
  for (uint32_t box = 0; box < boxes; ++box) {
    Counts atLo, atHi;
    if (weighted)
      countAround<true>(box, boxes, atLo, atHi);
    else
      countAround<false>(box, boxes, atLo, atHi);
    record(2 * box, lo_[box], atLo);
    record(2 * box + 1, hi_[box], atHi);
  }
  // The empty-space cuts: below the lowest lo, above the highest hi.
  const Float4 infinity = Float4{} + kInfinity, bonus = Float4{} + float(cost.emptyBonus);
  const Float4 cutLowCost = lowest > nodeLo ? (wholeArea - belowArea(lowest)) * all * bonus : infinity;
  const Float4 cutHighCost = highest < nodeHi ? belowArea(highest) * all * bonus : infinity;

  // Per axis, the cheapest of the three (the cuts first among equals), then
  // the lowest axis among equals.
  for (int axis = 0; axis < 3; ++axis) {
    const double splitCost = cost.splitBase + std::min({cutLowCost[axis], cutHighCost[axis], cheapest[axis]});
    if (!(splitCost < best.cost)) continue;
    best.cost = splitCost;
    if (cutLowCost[axis] <= cutHighCost[axis] && cutLowCost[axis] <= cheapest[axis]) {
      best.split = KdSplit{axis, lowest[axis], false};
    } else if (cutHighCost[axis] <= cheapest[axis]) {
      best.split = KdSplit{axis, highest[axis], true};
    } else {
      uint32_t k = 0;
      while (planarBelowCost_[k][axis] != cheapest[axis] && planarAboveCost_[k][axis] != cheapest[axis]) ++k;
      best.split = KdSplit{axis, k & 1 ? hi_[k / 2][axis] : lo_[k / 2][axis],
                           planarBelowCost_[k][axis] == cheapest[axis]};
    }
  }
}

// Binned SAH for nodes over kSmallNode triangles, in O(n): one pass counts
// the triangles' events in bins along the three axes; the costs at the bin
// boundaries choose the axis and the best boundary on it; a second pass
// collects that axis's events in the bins on either side of it, which are
// sorted and swept exactly (the counts of the bins before them start the
// sweep). The split is thus the exact SAH's best plane near the binned
// best, always on a face of a triangle's box.
class BinnedSplitter {
 public:
  explicit BinnedSplitter(uint32_t binCount) : binCount_(binCount), counts_(3 * binCount + 1) {}
  void findSplit(std::span<const Reference> references, const Box& box, const NodeCost& cost, BestSplit& best);

 private:
  // The bins of x along the three axes: they grow with x, so an event in a
  // lower bin than another lies strictly below it. An axis too thin to bin
  // has all its events in bin 0.
  struct Binning {
    Float4 origin, scale, last;
    Int4 operator()(Float4 x) const {
      // maxps and minps: t > 0 ? t : 0 (never negative, not even NaN),
      // then t < last ? t : last, one instruction each.
      const Float4 t = _mm_max_ps((x - origin) * scale, Float4{});
      return __builtin_convertvector(Float4(_mm_min_ps(t, last)), Int4);
    }
  };
  // The best boundary: its axis, and the bins on either side of it.
  struct Window {
    int axis;
    uint32_t first, last;
  };
  void countEvents(std::span<const Reference> references, const Binning& bin);
  std::optional<Window> chooseWindow(const NodeCost& cost) const;
  uint32_t collectEvents(std::span<const Reference> references, const Binning& bin, const Window& window);
  void sortEvents(Event* events, uint32_t count);
  const Int4* counts(uint32_t type) const { return counts_.data() + type * binCount_; }

  uint32_t binCount_;
  // Per event type and bin, the events there along each axis (in lanes).
  // The ends count the flat boxes too (as if they ended where they lie, in
  // the bin of their planar event: one select less per reference), so the
  // ends of a bin are counts(kEnd) - counts(kPlanar); the last entry is
  // unused.
  std::vector<Int4> counts_;
  std::vector<Event> events_;
  std::vector<Event> scratch_;  // sortEvents'
};

void BinnedSplitter::countEvents(std::span<const Reference> references, const Binning& bin) {
  std::fill(counts_.begin(), counts_.end(), Int4{});
  // Indices of the uint32_t counters: (type * binCount + bin) * 4 + axis.
  const Int4 lane = {0, 1, 2, 3};
  const Int4 starts = lane + int32_t(4 * kStart * binCount_), planars = lane + int32_t(4 * kPlanar * binCount_);
  const Int4 ends = lane + int32_t(4 * kEnd * binCount_), planarsFromStarts = planars - starts;
  uint32_t* const counters = reinterpret_cast<uint32_t*>(counts_.data());
  for (const Reference& reference : references) {
    const Float4 lo = reference.lo4(), hi = reference.hi4();
    const Int4 planar = lo == hi;
    const Int4 loIndex = starts + (planar & planarsFromStarts) + (bin(lo) << 2);
    const Int4 hiIndex = ends + (bin(hi) << 2);
    ++counters[loIndex[0]], ++counters[loIndex[1]], ++counters[loIndex[2]];
    ++counters[hiIndex[0]], ++counters[hiIndex[1]], ++counters[hiIndex[2]];
  }
}

// The cheapest inner bin boundary over the three axes at once (planar
// triangles below it; the lowest axis among equals), and the bins on
// either side of it, grown over empty bins so that they hold the events
// next to it. None when no axis can be split.
std::optional<BinnedSplitter::Window> BinnedSplitter::chooseWindow(const NodeCost& cost) const {
  const Float4 nodeLo = cost.lo, nodeHi = cost.hi, perimeter = cost.perimeter, cross = cost.cross;
  const float emptyBonus = float(cost.emptyBonus);
  const Float4 width = (nodeHi - nodeLo) / float(binCount_);
  const Float4 wholeArea = (nodeHi - nodeLo) * perimeter + cross + cross;
  const Int4* const starts = counts(kStart);
  const Int4* const ends = counts(kEnd);
  const Int4* const planars = counts(kPlanar);
  Int4 below = {}, above = Int4{} + int32_t(cost.count);
  Float4 bestCost = Float4{} + kInfinity;
  Int4 bestBoundary = Int4{} + 1;
  for (uint32_t boundary = 1; boundary < binCount_; ++boundary) {
    below += starts[boundary - 1] + planars[boundary - 1];
    above -= ends[boundary - 1];  // with the planars (see counts_)
    const Float4 belowArea = width * float(boundary) * perimeter + cross, aboveArea = wholeArea - belowArea;
    Float4 boundaryCost = belowArea * __builtin_convertvector(below, Float4) + aboveArea * __builtin_convertvector(above, Float4);
    boundaryCost = (below == 0) | (above == 0) ? boundaryCost * emptyBonus : boundaryCost;
    const Int4 better = boundaryCost < bestCost;
    bestCost = better ? boundaryCost : bestCost;
    bestBoundary = better ? Int4{} + int32_t(boundary) : bestBoundary;
  }
  int axis = -1;
  for (int lane = 0; lane < 3; ++lane)
    if (bestCost[lane] < kInfinity && (axis < 0 || bestCost[lane] < bestCost[axis])) axis = lane;
  if (axis < 0) return std::nullopt;
  const auto empty = [&](uint32_t bin) { return (starts[bin] + ends[bin])[axis] == 0; };  // ends: with planars
  Window window{axis, uint32_t(bestBoundary[axis]) - 1, uint32_t(bestBoundary[axis])};
  while (window.first > 0 && empty(window.first)) --window.first;
  while (window.last + 1 < binCount_ && empty(window.last)) ++window.last;
  return window;
}

// The events of the window's axis in its bins, sorted, into events_;
// returns their count. A reference lying wholly before or after the window
// (most of them) is passed over after two comparisons with positions just
// outside it; the others' events are written whether in the window or not,
// and kept when in it (no branch to mispredict). Their bins are computed
// again, on one axis, by the same operations as Binning's lanes (cheaper
// than storing and reloading them per reference).
uint32_t BinnedSplitter::collectEvents(std::span<const Reference> references, const Binning& bin,
                                       const Window& window) {
  if (events_.size() < 2 * references.size()) events_.resize(2 * references.size());
  Event* const events = events_.data();
  const int axis = window.axis;
  const uint32_t span = window.last - window.first;
  const float origin = bin.origin[axis], scale = bin.scale[axis], last = bin.last[axis];
  const auto binOf = [&](float x) {
    float t = (x - origin) * scale;
    t = t > 0.0f ? t : 0.0f;
    return uint32_t(int32_t(t < last ? t : last));
  };
  // Positions a hundredth of a bin outside the window: a float x below
  // before has (x - origin) * scale <= first - 0.01 exactly, so under first
  // however binOf rounds (its error is ~1e-7 of the bins); likewise a float
  // at or after `after` is in a bin past last. NaN-free: scale > 0 here
  // (chooseWindow never picks a flat axis).
  float before = -kInfinity, after = kInfinity;
  if (window.first > 0) {
    const double x = double(origin) + (double(window.first) - 0.01) / double(scale);
    before = float(x);
    if (double(before) > x) before = std::nextafter(before, -kInfinity);
  }
  if (window.last + 1 < binCount_) {
    const double x = double(origin) + (double(window.last + 1) + 0.01) / double(scale);
    after = float(x);
    if (double(after) < x) after = std::nextafter(after, kInfinity);
  }
  uint32_t count = 0;
  for (const Reference& reference : references) {
    const float lo = reference.lo[axis], hi = reference.hi[axis];
    if (hi < before || lo >= after) continue;
    const bool planar = lo == hi;
    const uint32_t loBin = binOf(lo), hiBin = binOf(hi);
    events[count] = makeEvent(lo, planar ? kPlanar : kStart);
    count += loBin - window.first <= span;
    events[count] = makeEvent(hi, kEnd);
    count += !planar & (hiBin - window.first <= span);
  }
  sortEvents(events, count);
  return count;
}

// Sorts events: up to 256 by std::sort; more by an LSD radix sort (8-bit
// digits) of their offsets from the lowest, which within a window span far
// fewer than 64 bits, so it takes a few passes without the comparison
// sort's mispredicted branches. perf, 500 K hall: sorting ~6.3 % of the
// build with std::sort alone, ~4.4 % so (~4.3 % with radix from 64).
void BinnedSplitter::sortEvents(Event* events, uint32_t count) {
  if (count <= 256) return std::sort(events, events + count);
  Event lowest = events[0], highest = events[0];
  for (uint32_t i = 1; i < count; ++i) {
    lowest = std::min(lowest, events[i]);
    highest = std::max(highest, events[i]);
  }
  if (lowest == highest) return;
  const int bits = 64 - std::countl_zero(highest - lowest);
  if (scratch_.size() < count) scratch_.resize(count);
  Event* from = events;
  Event* to = scratch_.data();
  for (int shift = 0; shift < bits; shift += 8) {
    uint32_t offsets[256] = {};
    for (uint32_t i = 0; i < count; ++i) ++offsets[((from[i] - lowest) >> shift) & 255];
    uint32_t sum = 0;
    for (uint32_t& offset : offsets) {
      const uint32_t digits = offset;
      offset = sum;
      sum += digits;
    }
    for (uint32_t i = 0; i < count; ++i) to[offsets[((from[i] - lowest) >> shift) & 255]++] = from[i];
    std::swap(from, to);
  }
  if (from != events) std::memcpy(events, from, count * sizeof(Event));
}

void BinnedSplitter::findSplit(std::span<const Reference> references, const Box& box, const NodeCost& cost,
                               BestSplit& best) {
  Binning bin{{}, {}, Float4{} + float(binCount_ - 1)};
  for (int axis = 0; axis < 3; ++axis) {
    const float scale = float(binCount_) / (box.hi[axis] - box.lo[axis]);
    bin.origin[axis] = box.lo[axis];
    bin.scale[axis] = std::isfinite(scale) ? scale : 0.0f;
  }
  bin.origin[3] = bin.origin[2];
  bin.scale[3] = bin.scale[2];
  countEvents(references, bin);
  const std::optional<Window> window = chooseWindow(cost);
  if (!window) return;
  // The sweep starts with the triangles whose events lie before the window.
  Int4 below = {}, above = Int4{} + int32_t(references.size());
  for (uint32_t b = 0; b < window->first; ++b) {
    below += counts(kStart)[b] + counts(kPlanar)[b];
    above -= counts(kEnd)[b];  // with the planars (see counts_)
  }
  const uint32_t count = collectEvents(references, bin, *window);
  const int axis = window->axis;
  sweep({events_.data(), count}, uint32_t(below[axis]), uint32_t(above[axis]), cost.plane(axis), axis, best);
}

class SahBuilder {
 public:
  SahBuilder(const MeshView& mesh, const KdTreeOptions& options, const KdBuildLimits& limits,
             KdTreeData& tree)
      : mesh_(mesh),
        limits_(limits),
        splitFactor_(options.traversalCost / options.intersectionCost),
        emptyBonus_(options.emptyBonus),
        writer_(tree),
        binnedSplitter_(uint32_t(options.bins)) {}

  std::vector<Reference>& arena() { return arena_; }
  void build(const Bounds3& bounds) {
    const Box box{{bounds.lo.x, bounds.lo.y, bounds.lo.z}, {bounds.hi.x, bounds.hi.y, bounds.hi.z}};
    buildNode(writer_.root(), 0, uint32_t(arena_.size()), box, 1);
  }

 private:
  std::optional<KdSplit> findSplit(std::span<const Reference> references, const Box& box);
  void buildNode(uint32_t node, size_t begin, uint32_t count, const Box& box, uint32_t depth);
  template <bool PlanarBelow>
  std::pair<uint32_t, uint32_t> splitReferences(size_t begin, uint32_t count, const KdSplit& split);
  bool splitCannotWin(std::span<const Reference> references, const Box& box) const;
  void makeLeaf(uint32_t node, std::span<const Reference> references, uint32_t depth);

  const MeshView& mesh_;
  KdBuildLimits limits_;
  double splitFactor_, emptyBonus_;  // traversal / intersection cost; the empty-space factor
  KdTreeWriter writer_;
  // The references of the nodes still to build, used as a stack: a node's
  // are at the top; its children's go on top of it (splitReferences).
  std::vector<Reference> arena_;
  // Scratch, reused from node to node (only before recursing).
  std::vector<uint32_t> leafTriangles_;
  SmallNodeSplitter smallNodeSplitter_;
  BinnedSplitter binnedSplitter_;
};

std::optional<KdSplit> SahBuilder::findSplit(std::span<const Reference> references, const Box& box) {
  constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
  // The three axes in lanes (most nodes are tiny: this setup counts). Per
  // axis, the two other sides: side1 the next axis, side2 the one after.
  const Float4 lo = {box.lo[0], box.lo[1], box.lo[2], kNaN}, hi = {box.hi[0], box.hi[1], box.hi[2], kNaN};
  const Float4 extent = hi - lo;
  const Float4 side1 = __builtin_shufflevector(extent, extent, 1, 2, 0, 3);
  const Float4 side2 = __builtin_shufflevector(extent, extent, 2, 0, 1, 3);
  const Int4 axes = {-1, -1, -1, 0};
  const Int4 thick = extent > 0.0f;  // flat axes (every plane a face) and lane 3 get NaN bounds
  NodeCost cost{thick ? lo : kNaN, thick ? hi : kNaN, axes ? side1 + side2 : 0.0f, axes ? side1 * side2 : 0.0f,
                0, 0, emptyBonus_, uint32_t(references.size())};
  // Each pair of faces once, in double (exact products).
  cost.halfArea = double(extent[1]) * extent[2];
  cost.halfArea += double(extent[2]) * extent[0];
  cost.halfArea += double(extent[0]) * extent[1];
  if (!(cost.halfArea > 0)) return std::nullopt;
  cost.splitBase = cost.halfArea * splitFactor_;
  BestSplit best{cost.halfArea * cost.count, std::nullopt};  // a split must beat the leaf
  if (cost.count > kSmallNode)
    binnedSplitter_.findSplit(references, box, cost, best);
  else
    smallNodeSplitter_.findSplit(references, cost, best);
  return best.split;
}

// Whether no split of the node can cost less than its leaf, by a lower
// bound on every split's cost: a triangle is counted in each child its box
// reaches, that child's area is at least that of the box's part in it, and
// the parts of a box cut in two have at least its area together; the
// empty-space factor is the most that scales a cost down. So every split
// costs at least A traversal / intersection + empty * sum of the boxes'
// areas. Nodes fitting tightly around one or two triangles (a quad's) end
// here without the SAH, which would find the same. The margin (0.1 %)
// leaves the close calls, and any rounding, to the SAH: the same trees.
bool SahBuilder::splitCannotWin(std::span<const Reference> references, const Box& box) const {
  const auto halfArea = [](Float4 extent) {
    return double(extent[1]) * extent[2] + double(extent[2]) * extent[0] + double(extent[0]) * extent[1];
  };
  const double nodeArea = halfArea(Float4{box.hi[0], box.hi[1], box.hi[2], 0} - Float4{box.lo[0], box.lo[1], box.lo[2], 0});
  double boxAreas = 0;
  for (const Reference& reference : references) boxAreas += halfArea(reference.hi4() - reference.lo4());
  return nodeArea * splitFactor_ + std::min(emptyBonus_, 1.0) * boxAreas > 1.001 * nodeArea * double(references.size());
}

void SahBuilder::makeLeaf(uint32_t node, std::span<const Reference> references, uint32_t depth) {
  if (references.size() <= 2) {  // most leaves: no vector, no sort call
    uint32_t triangles[2] = {};
    if (references.size() > 0) triangles[0] = references[0].primitive;
    if (references.size() > 1) {
      triangles[1] = references[1].primitive;
      if (triangles[1] < triangles[0]) std::swap(triangles[0], triangles[1]);
    }
    return writer_.leaf(node, {triangles, references.size()}, depth);
  }
  leafTriangles_.clear();
  for (const Reference& reference : references) leafTriangles_.push_back(reference.primitive);
  std::sort(leafTriangles_.begin(), leafTriangles_.end());
  writer_.leaf(node, leafTriangles_, depth);
}

// Writes the node's children's references: above's in place at begin,
// below's just past the node's range (at begin + count), where the below
// child, built first, is then the top of the stack; the gap between them is
// left unused until the node's subtree is done. No copy of either side.
// Straddling triangles are clipped to each child (perfect splits). Returns
// the counts of below and above.
template <bool PlanarBelow>
std::pair<uint32_t, uint32_t> SahBuilder::splitReferences(size_t begin, uint32_t count, const KdSplit& split) {
  // Each reference gives at most one to each side.
  if (arena_.size() < begin + 2 * size_t(count)) arena_.resize(begin + 2 * size_t(count));
  Reference* const references = arena_.data() + begin;
  Reference* const below = references + count;
  // Each reference gives at most one to above, so above's, written in place,
  // never overtake the one being read.
  uint32_t aboveCount = 0, belowCount = 0;
  const int axis = split.axis;
  const float position = split.position;
  for (uint32_t i = 0; i < count; ++i) {
    // As kdSideOf, without branches (which side is a coin toss): lo <= hi,
    // so a box ending on the plane goes below unless it lies in it with the
    // planar triangles above; and the other way round. (PlanarBelow a
    // template parameter: two comparisons and an and, not five operations.)
    const float lo = references[i].lo[axis], hi = references[i].hi[axis];
    const bool toBelow = PlanarBelow ? hi <= position : (hi <= position) & (lo < position);
    const bool toAbove = PlanarBelow ? (lo >= position) & (hi > position) : lo >= position;
    // Copied as two vectors (a struct copy goes through the stack).
    Float4 first, second;
    std::memcpy(&first, reinterpret_cast<const char*>(references + i), 16);
    std::memcpy(&second, reinterpret_cast<const char*>(references + i) + 16, 16);
    std::memcpy(reinterpret_cast<char*>(references + aboveCount), &first, 16);
    std::memcpy(reinterpret_cast<char*>(references + aboveCount) + 16, &second, 16);
    std::memcpy(reinterpret_cast<char*>(below + belowCount), &first, 16);
    std::memcpy(reinterpret_cast<char*>(below + belowCount) + 16, &second, 16);
    aboveCount += toAbove;
    belowCount += toBelow;
    if (toBelow | toAbove) continue;
    // A straddler: references[i] is intact (above's writes there, if any,
    // were of itself); copied before the parts overwrite it.
    const Reference reference = references[i];
    if (count <= kClipAbove) {
      Reference part = reference;
      part.lo[axis] = position;
      references[aboveCount++] = part;
      part = reference;
      part.hi[axis] = position;
      below[belowCount++] = part;
      continue;
    }
    Vec3 v0, v1, v2;
    mesh_.triangle(reference.primitive, v0, v1, v2);
    Bounds3 belowPart, abovePart;
    splitTriangleToChildren(v0, v1, v2, reference.bounds(), axis, position, belowPart, abovePart);
    if (!abovePart.empty()) references[aboveCount++] = Reference::of(abovePart, reference.primitive);
    if (!belowPart.empty()) below[belowCount++] = Reference::of(belowPart, reference.primitive);
  }
  return {belowCount, aboveCount};
}

void SahBuilder::buildNode(uint32_t node, size_t begin, uint32_t count, const Box& box, uint32_t depth) {
  const std::span<const Reference> references(arena_.data() + begin, count);
  if (count <= limits_.leafSize || depth > limits_.maxDepth) return makeLeaf(node, references, depth);
  if (count <= kTinyNode && splitCannotWin(references, box)) return makeLeaf(node, references, depth);
  const std::optional<KdSplit> split = findSplit(references, box);
  if (!split) return makeLeaf(node, references, depth);
  const auto [belowCount, aboveCount] = split->planarBelow ? splitReferences<true>(begin, count, *split)
                                                           : splitReferences<false>(begin, count, *split);
  // The gap left below the below child's references costs memory only
  // while the subtree is built; a large node whose above child kept much
  // less than its below child got (an empty-space cut) closes it, so that
  // the stack stays within twice the references of a path (no copy else).
  size_t belowBegin = begin + count;
  if (count >= 1024 && count - aboveCount >= belowCount) {
    std::memmove(arena_.data() + begin + aboveCount, arena_.data() + belowBegin, belowCount * sizeof(Reference));
    belowBegin = begin + aboveCount;
  }
  const uint32_t children = writer_.split(node, split->axis, split->position);
  buildNode(children, belowBegin, belowCount, box.below(split->axis, split->position), depth + 1);
  buildNode(children + 1, begin, aboveCount, box.above(split->axis, split->position), depth + 1);
}

}  // namespace

void buildKdTreeSah(const MeshView& mesh, const KdTreeOptions& options, KdTreeData& tree) {
  const std::vector<uint32_t> triangles = kdTreeTriangles(mesh);
  if (triangles.empty()) return;
  SahBuilder builder(mesh, options, kdBuildLimits(options, triangles.size()), tree);
  std::vector<Reference>& arena = builder.arena();
  // The root's references, and room for their children's (straddlers
  // add a few): no regrowth and copy while the top of the tree is built.
  arena.reserve(3 * triangles.size());
  for (uint32_t primitive : triangles) {
    const Bounds3 box = mesh.triangleBounds(primitive);
    arena.push_back(Reference::of(box, primitive));
    tree.bounds.extend(box);
  }
  builder.build(tree.bounds);
}

}  // namespace portico
