// kd:bbox: the bounding-box heuristic of Szécsi (2003), as the paper
// describes it: the boxes of the node's triangles are sorted along the
// node's longest axis, and the split is the box boundary that leaves the
// larger child smallest: it balances the two sides and cuts few boxes (a
// straddling triangle counts on both sides). Sorting makes it O(n log n) per
// node; nothing is weighed by area, so empty space is not cut off.
#include <algorithm>

#include "common/accel/kd_build.h"

namespace portico {

namespace {

constexpr uint32_t kEnd = 0, kPlanar = 1, kStart = 2;

}  // namespace

std::optional<KdSplit> BoundingBoxSplitChooser::chooseOnAxis(
    std::span<const KdReference> references, const Bounds3& nodeBox, int axis, uint32_t& cost) {
  const float nodeLo = nodeBox.lo[axis], nodeHi = nodeBox.hi[axis];
  if (!(nodeLo < nodeHi)) return std::nullopt;
  boundaries_.clear();
  for (const KdReference& reference : references) {
    const float lo = reference.box.lo[axis] + 0.0f, hi = reference.box.hi[axis] + 0.0f;  // no -0
    if (lo == hi) {
      boundaries_.push_back({lo, kPlanar});
    } else {
      boundaries_.push_back({lo, kStart});
      boundaries_.push_back({hi, kEnd});
    }
  }
  std::sort(boundaries_.begin(), boundaries_.end(), [](const Boundary& a, const Boundary& b) {
    return a.position < b.position || (a.position == b.position && a.type < b.type);
  });

  // Sweep: at each boundary position, `below` counts the triangles that
  // reach below it, `above` those that reach above it, `planar` those lying
  // in it (they go to the smaller side).
  const uint32_t count = uint32_t(references.size());
  uint32_t below = 0, above = count;
  std::optional<KdSplit> best;
  uint32_t bestStraddling = 0;
  for (size_t i = 0; i < boundaries_.size();) {
    const float position = boundaries_[i].position;
    uint32_t ends = 0, planar = 0, starts = 0;
    while (i < boundaries_.size() && boundaries_[i].position == position && boundaries_[i].type == kEnd) ++ends, ++i;
    while (i < boundaries_.size() && boundaries_[i].position == position && boundaries_[i].type == kPlanar) ++planar, ++i;
    while (i < boundaries_.size() && boundaries_[i].position == position && boundaries_[i].type == kStart) ++starts, ++i;
    above -= planar + ends;
    const bool planarBelow = below <= above;
    const uint32_t belowCount = below + (planarBelow ? planar : 0);
    const uint32_t aboveCount = above + (planarBelow ? 0 : planar);
    const uint32_t larger = std::max(belowCount, aboveCount);
    const uint32_t straddling = belowCount + aboveCount - count;
    // A split on a face of the node only helps if it moves triangles out.
    const bool useful = larger < count && (position > nodeLo || belowCount > 0) &&
                        (position < nodeHi || aboveCount > 0);
    if (useful && (!best || larger < cost || (larger == cost && straddling < bestStraddling))) {
      best = KdSplit{axis, position, planarBelow};
      cost = larger;
      bestStraddling = straddling;
    }
    below += starts + planar;
  }
  return best;
}

std::optional<KdSplit> BoundingBoxSplitChooser::choose(std::span<const KdReference> references,
                                                       const Bounds3& nodeBox) {
  // The longest axis, as the paper sorts along one axis; the others only
  // when no boundary on it makes progress.
  const int longest = nodeBox.longestAxis();
  uint32_t cost = 0;
  if (std::optional<KdSplit> split = chooseOnAxis(references, nodeBox, longest, cost)) return split;
  std::optional<KdSplit> best;
  uint32_t bestCost = 0;
  for (int axis = 0; axis < 3; ++axis) {
    if (axis == longest) continue;
    uint32_t axisCost = 0;
    std::optional<KdSplit> split = chooseOnAxis(references, nodeBox, axis, axisCost);
    if (split && (!best || axisCost < bestCost)) best = split, bestCost = axisCost;
  }
  return best;
}

}  // namespace portico
