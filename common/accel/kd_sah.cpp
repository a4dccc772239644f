// kd:sah: the surface area heuristic, built in O(n log n) after Wald &
// Havran, "On building fast kd-trees for ray tracing, and on doing that in
// O(N log N)" (2006).
//
// Each node keeps, per axis, the sorted list of its triangles' events: where
// a triangle's (clipped) box starts and ends along the axis, or one planar
// event where the box is flat. Events are sorted once, at the root; a sweep
// over a node's lists evaluates every candidate plane in O(n); the chosen
// split classifies each triangle below, above or both, and the lists are
// split in one pass that preserves their order. Only the straddling
// triangles are clipped to the children (perfect splits), and their new
// events, sorted on their own, are merged in.
//
// Memory: the lists live in one arena used as a stack. A node's lists are
// at its top; its children's lists replace them (through a scratch copy),
// the above child's first, so that the below child, built first, is again
// at the top. No allocation per node, and the arena stays within a small
// multiple of the root's lists.
//
// Cost model: a leaf costs intersection * n; a split costs
//   traversal + intersection * (A_below * n_below + A_above * n_above) / A,
// times `empty` when one side of a plane strictly inside the node is empty.
// Triangles lying in the plane go to the side where they cost less, so the
// axis-aligned walls, floors and furniture faces of a building end up in
// thin leaves of their own. A node stays a leaf when no split is cheaper.
#include <algorithm>
#include <bit>
#include <cstring>
#include <optional>
#include <utility>

#include "common/accel/kd_build.h"

namespace portico {

namespace {

// Event types, in the order they sort at equal positions: the sweep must see
// a plane's ends before its planar triangles, and those before its starts.
constexpr uint32_t kEnd = 0, kPlanar = 1, kStart = 2;

struct Event {
  float position;
  uint32_t code;  // primitive << 2 | type
};

inline uint32_t typeOf(const Event& event) { return event.code & 3; }
inline uint32_t primitiveOf(const Event& event) { return event.code >> 2; }
inline bool sortsBefore(const Event& a, const Event& b) {
  return a.position < b.position || (a.position == b.position && typeOf(a) < typeOf(b));
}

// Maps floats (not NaN, no -0) to unsigned integers in the same order.
inline uint32_t orderedBits(float position) {
  const uint32_t bits = std::bit_cast<uint32_t>(position);
  return (bits & 0x80000000u) ? ~bits : bits | 0x80000000u;
}

// Stable LSD radix sort by position (11 + 11 + 10 bits), so that events
// generated ends first, then planars, then starts come out sorted by
// (position, type). The result is in events.
void radixSortByPosition(std::vector<Event>& events, std::vector<Event>& scratch) {
  scratch.resize(events.size());
  constexpr int kShift[3] = {0, 11, 22};
  constexpr uint32_t kMask[3] = {2047, 2047, 1023};
  for (int pass = 0; pass < 3; ++pass) {
    uint32_t offsets[2048] = {};
    for (const Event& event : events) ++offsets[(orderedBits(event.position) >> kShift[pass]) & kMask[pass]];
    // A digit shared by every event (the usual case for the top bits) needs no pass.
    if (std::find(std::begin(offsets), std::end(offsets), uint32_t(events.size())) != std::end(offsets)) continue;
    uint32_t sum = 0;
    for (uint32_t& offset : offsets) {
      const uint32_t bucket = offset;
      offset = sum;
      sum += bucket;
    }
    for (const Event& event : events)
      scratch[offsets[(orderedBits(event.position) >> kShift[pass]) & kMask[pass]]++] = event;
    events.swap(scratch);
  }
}

// Appends the events of a triangle whose box (within the node) is box.
inline void addEvents(std::vector<Event>* lists, const Bounds3& box, uint32_t primitive) {
  for (int axis = 0; axis < 3; ++axis) {
    const float lo = box.lo[axis] + 0.0f, hi = box.hi[axis] + 0.0f;  // + 0: no -0 events
    if (lo == hi) {
      lists[axis].push_back({lo, primitive << 2 | kPlanar});
    } else {
      lists[axis].push_back({lo, primitive << 2 | kStart});
      lists[axis].push_back({hi, primitive << 2 | kEnd});
    }
  }
}

// Where a node's three lists are in the arena: one after another.
struct NodeLists {
  size_t begin = 0;
  uint32_t size[3] = {0, 0, 0};
  uint32_t triangleCount = 0;

  size_t offset(int axis) const {
    return begin + (axis > 0 ? size[0] : 0) + (axis > 1 ? size[1] : 0);
  }
  size_t total() const { return size_t(size[0]) + size[1] + size[2]; }
};

enum Side : uint8_t { kBoth = 0, kBelow = 1, kAbove = 2 };

class SahBuilder {
 public:
  SahBuilder(const MeshView& mesh, const KdTreeOptions& options, const KdBuildLimits& limits,
             KdTreeData& tree)
      : mesh_(mesh),
        limits_(limits),
        traversalCost_(options.traversalCost),
        intersectionCost_(options.intersectionCost),
        emptyBonus_(options.emptyBonus),
        writer_(tree),
        side_(mesh.triangleCount) {}

  std::vector<Event>& arena() { return arena_; }
  void build(const NodeLists& root, const Bounds3& box) { buildNode(writer_.root(), root, box, 1); }

 private:
  std::optional<KdSplit> findSplit(const NodeLists& lists, const Bounds3& box) const;
  void buildNode(uint32_t node, const NodeLists& lists, const Bounds3& box, uint32_t depth);
  void makeLeaf(uint32_t node, const NodeLists& lists, uint32_t depth);

  const MeshView& mesh_;
  KdBuildLimits limits_;
  double traversalCost_, intersectionCost_, emptyBonus_;
  KdTreeWriter writer_;
  std::vector<Side> side_;  // per primitive: its side of the split being made
  std::vector<Event> arena_;
  // Scratch, reused from node to node (only before recursing).
  std::vector<Event> belowScratch_, aboveScratch_;
  std::vector<Event> newBelow_[3], newAbove_[3];
  std::vector<uint32_t> leafTriangles_;
};

// The sweep of Wald & Havran over each axis's sorted events. At a plane p,
// `below` counts the triangles reaching below p, `above` those reaching
// above it, `planar` those lying in it.
std::optional<KdSplit> SahBuilder::findSplit(const NodeLists& lists, const Bounds3& box) const {
  const Vec3 extent = box.diagonal();
  // Half areas throughout: the factor 2 cancels.
  const double halfArea = double(extent.x) * extent.y + double(extent.y) * extent.z +
                          double(extent.z) * extent.x;
  if (!(halfArea > 0)) return std::nullopt;
  const uint32_t count = lists.triangleCount;
  // Costs in units of the intersection cost, scaled by the node's area:
  // leaf = A * n; split = A * traversal / intersection + A_below n_below + A_above n_above.
  const double splitBase = halfArea * traversalCost_ / intersectionCost_;
  double bestCost = halfArea * count;  // a split must beat the leaf
  std::optional<KdSplit> best;
  for (int axis = 0; axis < 3; ++axis) {
    const float nodeLo = box.lo[axis], nodeHi = box.hi[axis];
    if (!(nodeLo < nodeHi)) continue;  // flat: every plane is a face
    const double side1 = extent[(axis + 1) % 3], side2 = extent[(axis + 2) % 3];
    const double perimeter = side1 + side2, cross = side1 * side2;
    const Event* const events = arena_.data() + lists.offset(axis);
    const uint32_t size = lists.size[axis];

    // Cost of the split at position with these counts; infinity when it
    // would leave a child equal to the node (a plane on a face that moves
    // nothing out).
    const auto splitCost = [&](float position, uint32_t belowCount, uint32_t aboveCount) {
      if ((position == nodeLo && aboveCount == count) || (position == nodeHi && belowCount == count))
        return double(kInfinity);
      const double belowArea = double(position - nodeLo) * perimeter + cross;
      const double aboveArea = double(nodeHi - position) * perimeter + cross;
      double cost = belowArea * belowCount + aboveArea * aboveCount;
      if ((belowCount == 0 || aboveCount == 0) && position > nodeLo && position < nodeHi) cost *= emptyBonus_;
      return splitBase + cost;
    };

    uint32_t below = 0, above = count;
    for (uint32_t i = 0; i < size;) {
      // The group of events at one position: ends, then planars, then starts.
      const float position = events[i].position;
      uint32_t ends = 0, planar = 0, starts = 0;
      do {
        const uint32_t type = typeOf(events[i]);
        ends += type == kEnd;
        planar += type == kPlanar;
        starts += type == kStart;
      } while (++i < size && events[i].position == position);
      above -= planar + ends;
      const double planarBelowCost = splitCost(position, below + planar, above);
      const double planarAboveCost = planar > 0 ? splitCost(position, below, above + planar) : kInfinity;
      if (planarBelowCost < bestCost || planarAboveCost < bestCost) {
        const bool planarBelow = planarBelowCost <= planarAboveCost;
        bestCost = planarBelow ? planarBelowCost : planarAboveCost;
        best = KdSplit{axis, position, planarBelow};
      }
      below += starts + planar;
    }
  }
  return best;
}

void SahBuilder::makeLeaf(uint32_t node, const NodeLists& lists, uint32_t depth) {
  // Each triangle has one start or one planar event on every axis.
  leafTriangles_.clear();
  const Event* const events = arena_.data() + lists.offset(0);
  for (uint32_t i = 0; i < lists.size[0]; ++i)
    if (typeOf(events[i]) != kEnd) leafTriangles_.push_back(primitiveOf(events[i]));
  std::sort(leafTriangles_.begin(), leafTriangles_.end());
  writer_.leaf(node, leafTriangles_, depth);
}

// Merges the sorted runs a and b into out; returns the end of the output.
Event* mergeEvents(const Event* a, const Event* aEnd, const Event* b, const Event* bEnd, Event* out) {
  if (b == bEnd) {
    std::memcpy(out, a, size_t(aEnd - a) * sizeof(Event));
    return out + (aEnd - a);
  }
  return std::merge(a, aEnd, b, bEnd, out, [](const Event& x, const Event& y) { return sortsBefore(x, y); });
}

void SahBuilder::buildNode(uint32_t node, const NodeLists& lists, const Bounds3& box, uint32_t depth) {
  if (lists.triangleCount <= limits_.leafSize || depth > limits_.maxDepth)
    return makeLeaf(node, lists, depth);
  const std::optional<KdSplit> split = findSplit(lists, box);
  if (!split) return makeLeaf(node, lists, depth);
  const int splitAxis = split->axis;
  const float position = split->position;
  const Side planarSide = split->planarBelow ? kBelow : kAbove;

  // Classify, in one pass over the split axis's sorted events. Before the
  // plane: a start means "both" unless the triangle's end (also before, or
  // on, the plane) overrules it with "below". On the plane: ends below,
  // planars to their side, starts above. After it: starts and planars
  // above; ends change nothing.
  {
    const Event* const events = arena_.data() + lists.offset(splitAxis);
    const uint32_t size = lists.size[splitAxis];
    Side* const side = side_.data();
    uint32_t i = 0;
    for (; i < size && events[i].position < position; ++i)
      side[primitiveOf(events[i])] = typeOf(events[i]) == kStart ? kBoth : kBelow;
    for (; i < size && events[i].position == position; ++i) {
      const uint32_t type = typeOf(events[i]);
      side[primitiveOf(events[i])] = type == kEnd ? kBelow : type == kStart ? kAbove : planarSide;
    }
    for (; i < size; ++i)
      if (typeOf(events[i]) != kEnd) side[primitiveOf(events[i])] = kAbove;
  }

  // Straddling triangles (those still "both": they start before the plane
  // and end after it) are clipped to each child; their new events are sorted.
  const Bounds3 belowBox = boxBelow(box, splitAxis, position);
  const Bounds3 aboveBox = boxAbove(box, splitAxis, position);
  for (int axis = 0; axis < 3; ++axis) newBelow_[axis].clear(), newAbove_[axis].clear();
  uint32_t belowCount = 0, aboveCount = 0;
  {
    const Event* const events = arena_.data() + lists.offset(splitAxis);
    const uint32_t size = lists.size[splitAxis];
    for (uint32_t i = 0; i < size && events[i].position < position; ++i) {
      const uint32_t primitive = primitiveOf(events[i]);
      if (typeOf(events[i]) != kStart || side_[primitive] != kBoth) continue;
      Vec3 v0, v1, v2;
      mesh_.triangle(primitive, v0, v1, v2);
      Bounds3 belowPart, abovePart;
      clipTriangleToChildren(v0, v1, v2, box, splitAxis, position, belowPart, abovePart);
      if (!belowPart.empty()) addEvents(newBelow_, belowPart, primitive), ++belowCount;
      if (!abovePart.empty()) addEvents(newAbove_, abovePart, primitive), ++aboveCount;
    }
  }
  const auto before = [](const Event& x, const Event& y) { return sortsBefore(x, y); };
  for (int axis = 0; axis < 3; ++axis) {
    std::sort(newBelow_[axis].begin(), newBelow_[axis].end(), before);
    std::sort(newAbove_[axis].begin(), newAbove_[axis].end(), before);
  }

  // Split each list in order into the scratch buffers, without branching on
  // the side (a coin toss for the predictor): every event is written to
  // both, and kept where it belongs.
  const size_t total = lists.total();
  if (belowScratch_.size() < total) belowScratch_.resize(total), aboveScratch_.resize(total);
  uint32_t filteredBelow[3], filteredAbove[3];
  {
    Event* outBelow = belowScratch_.data();
    Event* outAbove = aboveScratch_.data();
    const Side* const side = side_.data();
    for (int axis = 0; axis < 3; ++axis) {
      const Event* const events = arena_.data() + lists.offset(axis);
      const uint32_t size = lists.size[axis];
      Event* const startBelow = outBelow;
      Event* const startAbove = outAbove;
      for (uint32_t i = 0; i < size; ++i) {
        const Event event = events[i];
        const Side s = side[primitiveOf(event)];
        *outBelow = event;
        *outAbove = event;
        outBelow += s == kBelow;
        outAbove += s == kAbove;
        if (axis == 0) {
          const uint32_t triangle = typeOf(event) != kEnd;
          belowCount += triangle & (s == kBelow);
          aboveCount += triangle & (s == kAbove);
        }
      }
      filteredBelow[axis] = uint32_t(outBelow - startBelow);
      filteredAbove[axis] = uint32_t(outAbove - startAbove);
    }
  }

  // The children's lists replace the node's in the arena: above first, so
  // that below, built first, is at the top.
  NodeLists above, below;
  above.begin = lists.begin;
  above.triangleCount = aboveCount;
  below.triangleCount = belowCount;
  size_t needed = 0;
  for (int axis = 0; axis < 3; ++axis) {
    above.size[axis] = filteredAbove[axis] + uint32_t(newAbove_[axis].size());
    below.size[axis] = filteredBelow[axis] + uint32_t(newBelow_[axis].size());
    needed += size_t(above.size[axis]) + below.size[axis];
  }
  below.begin = above.begin + above.total();
  if (arena_.size() < lists.begin + needed) arena_.resize(lists.begin + needed);
  {
    Event* out = arena_.data() + above.begin;
    const Event* in = aboveScratch_.data();
    for (int axis = 0; axis < 3; ++axis) {
      out = mergeEvents(in, in + filteredAbove[axis], newAbove_[axis].data(),
                        newAbove_[axis].data() + newAbove_[axis].size(), out);
      in += filteredAbove[axis];
    }
    in = belowScratch_.data();
    for (int axis = 0; axis < 3; ++axis) {
      out = mergeEvents(in, in + filteredBelow[axis], newBelow_[axis].data(),
                        newBelow_[axis].data() + newBelow_[axis].size(), out);
      in += filteredBelow[axis];
    }
  }

  const uint32_t children = writer_.split(node, splitAxis, position);
  buildNode(children, below, belowBox, depth + 1);
  buildNode(children + 1, above, aboveBox, depth + 1);
}

}  // namespace

void buildKdTreeSah(const MeshView& mesh, const KdTreeOptions& options, KdTreeData& tree) {
  const std::vector<uint32_t> triangles = kdTreeTriangles(mesh);
  if (triangles.empty()) return;
  SahBuilder builder(mesh, options, kdBuildLimits(options, triangles.size()), tree);

  // The root's events, generated ends, then planars, then starts, so that
  // the stable sort by position leaves equal positions in type order.
  std::vector<Bounds3> boxes(triangles.size());
  for (size_t i = 0; i < triangles.size(); ++i) {
    boxes[i] = mesh.triangleBounds(triangles[i]);
    tree.bounds.extend(boxes[i]);
  }
  NodeLists root;
  root.triangleCount = uint32_t(triangles.size());
  std::vector<Event>& arena = builder.arena();
  std::vector<Event> list, scratch;
  for (int axis = 0; axis < 3; ++axis) {
    list.clear();
    for (uint32_t type : {kEnd, kPlanar, kStart}) {
      for (size_t i = 0; i < triangles.size(); ++i) {
        const float lo = boxes[i].lo[axis] + 0.0f, hi = boxes[i].hi[axis] + 0.0f;  // no -0
        const uint32_t code = triangles[i] << 2 | type;
        if (lo == hi) {
          if (type == kPlanar) list.push_back({lo, code});
        } else if (type != kPlanar) {
          list.push_back({type == kStart ? lo : hi, code});
        }
      }
    }
    radixSortByPosition(list, scratch);
    root.size[axis] = uint32_t(list.size());
    arena.insert(arena.end(), list.begin(), list.end());
  }
  std::vector<Bounds3>().swap(boxes);
  std::vector<Event>().swap(list);
  std::vector<Event>().swap(scratch);
  builder.build(root, tree.bounds);
}

}  // namespace portico
