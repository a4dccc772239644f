// kd:sah: the surface area heuristic (header comment rewritten at the end of this change).
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <span>
#include <utility>
#include <vector>

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

// Appends the events of box along axis.
inline void addEvents(std::vector<Event>& events, const Bounds3& box, int axis) {
  const float lo = box.lo[axis], hi = box.hi[axis];
  if (lo == hi) {
    events.push_back(makeEvent(lo, kPlanar));
  } else {
    events.push_back(makeEvent(lo, kStart));
    events.push_back(makeEvent(hi, kEnd));
  }
}

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

// Four lanes at once (GCC and Clang vector extensions: SSE on x86-64).
using Float4 = float __attribute__((vector_size(16)));
using Int4 = int32_t __attribute__((vector_size(16)));

// Nodes of at most this many triangles are split by counting, not sorting.
constexpr uint32_t kSmallNode = 16;

// The exact SAH of a small node without sorting: every face of every box is
// a candidate plane, and its counts below, above and in it come from
// comparing it with every box, four candidates at a time. O(n^2), but with
// no branches and no per-node setup it beats sorting up to kSmallNode.
class SmallNodeSplitter {
 public:
  void findSplit(std::span<const KdReference> references, const PlaneCost& cost, int axis, BestSplit& best);

 private:
  // Per box along the axis, in all four lanes: its ends, and its position
  // when it is flat there (else NaN, equal to nothing).
  Float4 lo_[kSmallNode], hi_[kSmallNode], planar_[kSmallNode];
  alignas(16) float candidates_[2 * kSmallNode + 3];
};

void SmallNodeSplitter::findSplit(std::span<const KdReference> references, const PlaneCost& cost, int axis,
                                  BestSplit& best) {
  const uint32_t count = uint32_t(references.size());
  constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
  uint32_t candidateCount = 0;
  for (uint32_t j = 0; j < count; ++j) {
    const float lo = references[j].box.lo[axis] + 0.0f, hi = references[j].box.hi[axis] + 0.0f;  // no -0
    lo_[j] = Float4{} + lo;
    hi_[j] = Float4{} + hi;
    planar_[j] = Float4{} + (lo == hi ? lo : kNaN);
    candidates_[candidateCount++] = lo;
    if (lo != hi) candidates_[candidateCount++] = hi;
  }
  while (candidateCount % 4) candidates_[candidateCount++] = kNaN;  // NaN costs never win

  const Float4 nodeLo = Float4{} + cost.nodeLo, nodeHi = Float4{} + cost.nodeHi;
  const Float4 perimeter = Float4{} + float(cost.perimeter), cross = Float4{} + float(cost.cross);
  const Float4 splitBase = Float4{} + float(cost.splitBase), emptyBonus = Float4{} + float(cost.emptyBonus);
  const Int4 all = Int4{} + int32_t(count);
  const Float4 infinity = Float4{} + kInfinity;
  // As PlaneCost, four planes at once.
  const auto planeCost = [&](Float4 position, Int4 below, Int4 above, Float4 belowArea, Float4 aboveArea) {
    Float4 result = belowArea * __builtin_convertvector(below, Float4) + aboveArea * __builtin_convertvector(above, Float4);
    result = ((below == 0 || above == 0) && position > nodeLo && position < nodeHi) ? result * emptyBonus : result;
    result = ((position == nodeLo && above == all) || (position == nodeHi && below == all)) ? infinity : result + splitBase;
    return result;
  };
  // Per lane, the best so far: its cost and 2 * candidate + (planar above).
  Float4 laneCost = infinity;
  Int4 laneChoice = Int4{} - 1;
  for (uint32_t c = 0; c < candidateCount; c += 4) {
    Float4 position;
    std::memcpy(&position, candidates_ + c, sizeof(position));
    Int4 below = {}, above = {}, planar = {};
    for (uint32_t j = 0; j < count; ++j) {  // a true comparison is -1
      below -= lo_[j] < position;
      above -= hi_[j] > position;
      planar -= planar_[j] == position;
    }
    const Float4 belowArea = (position - nodeLo) * perimeter + cross;
    const Float4 aboveArea = (nodeHi - position) * perimeter + cross;
    const Int4 choice = (Int4{0, 2, 4, 6} + int32_t(2 * c));
    const Float4 planarBelowCost = planeCost(position, below + planar, above, belowArea, aboveArea);
    Int4 better = planarBelowCost < laneCost;
    laneCost = better ? planarBelowCost : laneCost;
    laneChoice = better ? choice : laneChoice;
    const Float4 planarAboveCost = planar > 0 ? planeCost(position, below, above + planar, belowArea, aboveArea) : infinity;
    better = planarAboveCost < laneCost;
    laneCost = better ? planarAboveCost : laneCost;
    laneChoice = better ? choice + 1 : laneChoice;
  }
  // The lanes' best, the earliest candidate among equals.
  int bestLane = -1;
  for (int lane = 0; lane < 4; ++lane) {
    if (laneChoice[lane] < 0) continue;
    if (bestLane < 0 || laneCost[lane] < laneCost[bestLane] ||
        (laneCost[lane] == laneCost[bestLane] && laneChoice[lane] < laneChoice[bestLane]))
      bestLane = lane;
  }
  if (bestLane >= 0 && laneCost[bestLane] < best.cost) {
    best.cost = laneCost[bestLane];
    best.split = KdSplit{axis, candidates_[laneChoice[bestLane] / 2], (laneChoice[bestLane] & 1) == 0};
  }
}

// Bins along one axis of a node: bin(x) grows with x, so a triangle whose
// event is in a lower bin than another's has it strictly below the other.
struct Binning {
  float lo, scale;
  uint32_t last;
  uint32_t operator()(float x) const { return std::min(uint32_t((x - lo) * scale), last); }
};

constexpr uint32_t kMaxBins = 256;

// Per bin, along one axis: the events of each type whose position falls in it.
struct AxisBins {
  uint32_t counts[3][kMaxBins];  // [type][bin]
};

// Bins [first, last] of an axis, where the exact sweep looks.
struct Window {
  uint32_t first, last;
};

class SahBuilder {
 public:
  SahBuilder(const MeshView& mesh, const KdTreeOptions& options, const KdBuildLimits& limits,
             KdTreeData& tree)
      : mesh_(mesh),
        limits_(limits),
        traversalCost_(options.traversalCost),
        intersectionCost_(options.intersectionCost),
        emptyBonus_(options.emptyBonus),
        binCount_(uint32_t(options.bins)),
        writer_(tree) {}

  std::vector<KdReference>& arena() { return arena_; }
  void build(const Bounds3& box) { buildNode(writer_.root(), 0, uint32_t(arena_.size()), box, 1); }

 private:
  std::optional<KdSplit> findSplit(std::span<const KdReference> references, const Bounds3& box);
  Window chooseWindow(std::span<const KdReference> references, const PlaneCost& cost, int axis,
                      const Binning& bin);
  void buildNode(uint32_t node, size_t begin, uint32_t count, const Bounds3& box, uint32_t depth);
  std::pair<uint32_t, uint32_t> splitReferences(size_t begin, uint32_t count, const KdSplit& split);
  void makeLeaf(uint32_t node, std::span<const KdReference> references, uint32_t depth);

  const MeshView& mesh_;
  KdBuildLimits limits_;
  double traversalCost_, intersectionCost_, emptyBonus_;
  uint32_t binCount_;
  KdTreeWriter writer_;
  // The references of the nodes still to build, used as a stack: a node's
  // are at the top; its children's replace them.
  std::vector<KdReference> arena_;
  // Scratch, reused from node to node (only before recursing).
  std::vector<Event> events_;
  std::vector<KdReference> belowScratch_;
  std::vector<uint32_t> leafTriangles_;
  AxisBins bins_;
  SmallNodeSplitter smallNodeSplitter_;
};

// Binned SAH (with binCount_ bins) to find where along axis the best plane
// lies, then the window of bins around it.
Window SahBuilder::chooseWindow(std::span<const KdReference> references, const PlaneCost& cost, int axis,
                                const Binning& bin) {
  const uint32_t binCount = bin.last + 1;
  for (auto& counts : bins_.counts) std::fill(counts, counts + binCount, 0u);
  for (const KdReference& reference : references) {
    const float lo = reference.box.lo[axis], hi = reference.box.hi[axis];
    if (lo == hi) {
      ++bins_.counts[kPlanar][bin(lo)];
    } else {
      ++bins_.counts[kStart][bin(lo)];
      ++bins_.counts[kEnd][bin(hi)];
    }
  }
  // The cost at each inner bin boundary, planar triangles below.
  const float width = (cost.nodeHi - cost.nodeLo) / float(binCount);
  uint32_t below = 0, above = cost.count, bestBoundary = 1;
  double bestCost = kInfinity;
  for (uint32_t boundary = 1; boundary < binCount; ++boundary) {
    below += bins_.counts[kStart][boundary - 1] + bins_.counts[kPlanar][boundary - 1];
    above -= bins_.counts[kEnd][boundary - 1] + bins_.counts[kPlanar][boundary - 1];
    const double boundaryCost = cost(cost.nodeLo + width * float(boundary), below, above);
    if (boundaryCost < bestCost) bestCost = boundaryCost, bestBoundary = boundary;
  }
  // The bins on either side of the best boundary, grown over empty bins so
  // that the window holds the events next to it.
  const auto empty = [&](uint32_t b) {
    return bins_.counts[kStart][b] + bins_.counts[kEnd][b] + bins_.counts[kPlanar][b] == 0;
  };
  Window window{bestBoundary - 1, bestBoundary};
  while (window.first > 0 && empty(window.first)) --window.first;
  while (window.last + 1 < binCount && empty(window.last)) ++window.last;
  return window;
}

std::optional<KdSplit> SahBuilder::findSplit(std::span<const KdReference> references, const Bounds3& box) {
  const Vec3 extent = box.diagonal();
  const double halfArea = double(extent.x) * extent.y + double(extent.y) * extent.z +
                          double(extent.z) * extent.x;
  if (!(halfArea > 0)) return std::nullopt;
  const uint32_t count = uint32_t(references.size());
  BestSplit best{halfArea * count, std::nullopt};  // a split must beat the leaf
  for (int axis = 0; axis < 3; ++axis) {
    const float nodeLo = box.lo[axis], nodeHi = box.hi[axis];
    if (!(nodeLo < nodeHi)) continue;  // flat: every plane is a face
    const double side1 = extent[(axis + 1) % 3], side2 = extent[(axis + 2) % 3];
    const PlaneCost cost{nodeLo, nodeHi, side1 + side2, side1 * side2, halfArea * traversalCost_ / intersectionCost_,
                         emptyBonus_, count};
    if (count <= kSmallNode) {
      smallNodeSplitter_.findSplit(references, cost, axis, best);
      continue;
    }
    events_.clear();
    uint32_t below = 0, above = count;
    const float scale = float(binCount_) / (nodeHi - nodeLo);
    if (std::isfinite(scale)) {
      const Binning bin{nodeLo, scale, binCount_ - 1};
      const Window window = chooseWindow(references, cost, axis, bin);
      for (uint32_t b = 0; b < window.first; ++b) {
        below += bins_.counts[kStart][b] + bins_.counts[kPlanar][b];
        above -= bins_.counts[kEnd][b] + bins_.counts[kPlanar][b];
      }
      for (const KdReference& reference : references) {
        const float lo = reference.box.lo[axis], hi = reference.box.hi[axis];
        const uint32_t loBin = bin(lo), hiBin = bin(hi);
        const bool loIn = loBin >= window.first && loBin <= window.last;
        const bool hiIn = hiBin >= window.first && hiBin <= window.last;
        if (lo == hi) {
          if (loIn) events_.push_back(makeEvent(lo, kPlanar));
        } else {
          if (loIn) events_.push_back(makeEvent(lo, kStart));
          if (hiIn) events_.push_back(makeEvent(hi, kEnd));
        }
      }
    } else {
      for (const KdReference& reference : references) addEvents(events_, reference.box, axis);
    }
    std::sort(events_.begin(), events_.end());
    sweep(events_, below, above, cost, axis, best);
  }
  return best.split;
}

void SahBuilder::makeLeaf(uint32_t node, std::span<const KdReference> references, uint32_t depth) {
  leafTriangles_.clear();
  for (const KdReference& reference : references) leafTriangles_.push_back(reference.primitive);
  std::sort(leafTriangles_.begin(), leafTriangles_.end());
  writer_.leaf(node, leafTriangles_, depth);
}

// Replaces the node's references at begin by its children's: above's
// first, so that below's, built first, are at the top. Straddling triangles
// are clipped to each child (perfect splits). Returns the counts of below
// and above.
std::pair<uint32_t, uint32_t> SahBuilder::splitReferences(size_t begin, uint32_t count, const KdSplit& split) {
  if (belowScratch_.size() < count) belowScratch_.resize(count);
  KdReference* const references = arena_.data() + begin;
  KdReference* const below = belowScratch_.data();
  // Each reference gives at most one to above, so above's, written in place,
  // never overtake the one being read.
  uint32_t aboveCount = 0, belowCount = 0;
  for (uint32_t i = 0; i < count; ++i) {
    const KdReference reference = references[i];
    const KdSide side = kdSideOf(reference.box, split);
    if (side != KdSide::Both) {
      references[aboveCount] = reference;
      below[belowCount] = reference;
      aboveCount += side == KdSide::Above;
      belowCount += side == KdSide::Below;
      continue;
    }
    Vec3 v0, v1, v2;
    mesh_.triangle(reference.primitive, v0, v1, v2);
    Bounds3 belowPart, abovePart;
    clipTriangleToChildren(v0, v1, v2, reference.box, split.axis, split.position, belowPart, abovePart);
    if (!abovePart.empty()) references[aboveCount++] = {abovePart, reference.primitive};
    if (!belowPart.empty()) below[belowCount++] = {belowPart, reference.primitive};
  }
  if (arena_.size() < begin + aboveCount + belowCount) arena_.resize(begin + aboveCount + belowCount);
  std::memcpy(arena_.data() + begin + aboveCount, belowScratch_.data(), belowCount * sizeof(KdReference));
  return {belowCount, aboveCount};
}

void SahBuilder::buildNode(uint32_t node, size_t begin, uint32_t count, const Bounds3& box, uint32_t depth) {
  const std::span<const KdReference> references(arena_.data() + begin, count);
  if (count <= limits_.leafSize || depth > limits_.maxDepth) return makeLeaf(node, references, depth);
  const std::optional<KdSplit> split = findSplit(references, box);
  if (!split) return makeLeaf(node, references, depth);
  const auto [belowCount, aboveCount] = splitReferences(begin, count, *split);
  const uint32_t children = writer_.split(node, split->axis, split->position);
  buildNode(children, begin + aboveCount, belowCount, boxBelow(box, split->axis, split->position), depth + 1);
  buildNode(children + 1, begin, aboveCount, boxAbove(box, split->axis, split->position), depth + 1);
}

}  // namespace

void buildKdTreeSah(const MeshView& mesh, const KdTreeOptions& options, KdTreeData& tree) {
  const std::vector<uint32_t> triangles = kdTreeTriangles(mesh);
  if (triangles.empty()) return;
  SahBuilder builder(mesh, options, kdBuildLimits(options, triangles.size()), tree);
  std::vector<KdReference>& arena = builder.arena();
  arena.reserve(triangles.size());
  for (uint32_t primitive : triangles) {
    arena.push_back({mesh.triangleBounds(primitive), primitive});
    tree.bounds.extend(arena.back().box);
  }
  builder.build(tree.bounds);
}

}  // namespace portico
