// A kd-tree over points with buckets, for exact k-nearest-neighbour and
// fixed-radius queries: the photon map's tree.
//
// Layout: flat arrays and no pointers. Nodes in depth-first order (a left
// child follows its parent; the parent holds the right child's index). A
// leaf holds up to kLeafSize points in consecutive slots, and the slots are
// the points renumbered in leaf order (order() maps each slot to the
// point's number in the input, so that callers keep their per-point data in
// slot order and read it next to the coordinates). The coordinates are
// three arrays (x, y, z), followed by kLanes - 1 NaN slots: a query
// computes the squared distances of kLanes slots at once (point_lanes.h)
// and reads only the points within its bound. A bucket is one run of
// memory, where a tree of one point per node reads one node per level.
//
// Determinism: every query's answer is the accepted points of least
// (squared distance in float, slot), the distance
// dot(point - p, point - p) evaluated as in math.h: exact, whatever the
// tree's shape; and the tree and the slots depend only on the points and
// their order in the input.
#pragma once

#include <algorithm>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "common/math.h"
#include "common/transport/point_lanes.h"

namespace portico {

class PointKdTree {
 public:
  // The most points one tree holds: a leaf node packs its count in 30 bits.
  static constexpr size_t kMaxPoints = (size_t{1} << 30) - 1;
  static constexpr uint32_t kLeafSize = 16;

  PointKdTree() = default;
  // Builds over positions[0 .. n), all finite; the caller checks
  // n <= kMaxPoints.
  explicit PointKdTree(const std::vector<Vec3>& positions);

  size_t size() const { return pointCount_; }
  // For each slot, the index its point had in `positions`.
  const std::vector<uint32_t>& order() const { return order_; }
  // Frees order() once the caller has used it.
  void forgetOrder() { order_ = {}; }
  Vec3 position(uint32_t slot) const { return {x_[slot], y_[slot], z_[slot]}; }
  uint64_t bytes() const;

  // Candidates of a query: the squared distance's bits (a non-negative
  // float's bits order like the float) above the slot, so one integer
  // comparison orders by (distance, slot).
  static uint64_t candidateKey(float distanceSquared, uint32_t slot) {
    return (uint64_t{std::bit_cast<uint32_t>(distanceSquared)} << 32) | slot;
  }
  static float candidateDistanceSquared(uint64_t key) {
    return std::bit_cast<float>(static_cast<uint32_t>(key >> 32));
  }
  static uint32_t candidateSlot(uint64_t key) { return static_cast<uint32_t>(key); }

  // Exact k-NN over the slots `accept(slot)` lets through, with squared
  // distance <= maxRadiusSquared. Leaves heap[0, result) as a max-heap of
  // candidate keys; `heap` holds at least k entries (k >= 1).
  template <typename Accept>
  uint32_t search(const Vec3& p, uint32_t k, float maxRadiusSquared, Accept accept, uint64_t* heap) const;

  // Appends to `keys` the candidate key of every slot `accept(slot)` lets
  // through with squared distance <= radiusSquared, in no particular order.
  template <typename Accept>
  void within(const Vec3& p, float radiusSquared, Accept accept, std::vector<uint64_t>& keys) const;

 private:
  // Interior: split plane `split` on axis `axisOrLeaf` (0-2), every point
  // of the left subtree <= split <= every point of the right one; the left
  // child next in the array, the right one at `index`. Leaf: axisOrLeaf is
  // kLeaf | count << 2, its points in slots [index, index + count).
  struct Node {
    float split;
    uint32_t index;
    uint32_t axisOrLeaf;
  };
  static constexpr uint32_t kLeaf = 3;
  // Far children waiting, with the squared distance to their splitting
  // plane: one per level. The builder keeps the depth under kMostDepth.
  struct Pending {
    uint32_t node;
    float planeDistanceSquared;
  };
  static constexpr int kMostDepth = 72;

  friend class PointKdTreeBuilder;

  // Calls visit(firstSlot, slotEnd) for the leaves a query at p can reach
  // within `bound` (re-read after each leaf: a k-NN search narrows it).
  template <typename VisitLeaf>
  void forEachLeaf(const Vec3& p, const float& bound, VisitLeaf visit) const;
  // Calls found(slot, squared distance) for each slot of [slot, end) within
  // `bound`, in slot order.
  template <typename Found>
  void leafWithin(const PointLanes& lanes, uint32_t slot, uint32_t end, const float& bound, Found found) const;

  std::vector<Node> nodes_;
  std::vector<float> x_, y_, z_;   // per slot, then kLanes - 1 NaN
  std::vector<uint32_t> order_;
  size_t pointCount_ = 0;
};

template <typename VisitLeaf>
void PointKdTree::forEachLeaf(const Vec3& p, const float& bound, VisitLeaf visit) const {
  if (nodes_.empty()) return;
  Pending stack[kMostDepth];
  int pending = 0;
  uint32_t node = 0;
  for (;;) {
    // Descend to the leaf on the query's side, leaving the other sides for
    // later.
    const Node* current = &nodes_[node];
    while ((current->axisOrLeaf & 3) != kLeaf) {
      const float delta = p[static_cast<int>(current->axisOrLeaf)] - current->split;
      const uint32_t left = static_cast<uint32_t>(current - nodes_.data()) + 1;
      stack[pending++] = {delta > 0 ? left : current->index, delta * delta};
      current = &nodes_[delta > 0 ? current->index : left];
    }
    visit(current->index, current->index + (current->axisOrLeaf >> 2));
    // The next far side that can still hold a point within the bound.
    // Rounding is monotonic, so a point beyond a plane never computes
    // closer than the plane.
    for (;;) {
      if (pending == 0) return;
      const Pending next = stack[--pending];
      if (next.planeDistanceSquared <= bound) {
        node = next.node;
        break;
      }
    }
  }
}

template <typename Found>
void PointKdTree::leafWithin(const PointLanes& lanes, uint32_t slot, uint32_t end, const float& bound,
                             Found found) const {
  for (; slot < end; slot += PointLanes::kLanes) {
    float distanceSquared[PointLanes::kLanes];
    uint32_t inside = lanes.within(&x_[slot], &y_[slot], &z_[slot], bound, distanceSquared);
    // The last group of a leaf reads the next leaf's first slots.
    if (end - slot < PointLanes::kLanes) inside &= (1u << (end - slot)) - 1;
    for (; inside; inside &= inside - 1) {
      const int lane = std::countr_zero(inside);
      found(slot + lane, distanceSquared[lane]);
    }
  }
}

template <typename Accept>
uint32_t PointKdTree::search(const Vec3& p, uint32_t k, float maxRadiusSquared, Accept accept, uint64_t* heap) const {
  uint32_t found = 0;
  // Squared distance a candidate must not exceed: the radius until k are
  // found, then the k-th's distance (equal distance can still win on slot).
  float bound = maxRadiusSquared;
  const PointLanes lanes(p);
  forEachLeaf(p, bound, [&](uint32_t first, uint32_t end) {
    leafWithin(lanes, first, end, bound, [&](uint32_t slot, float distanceSquared) {
      const uint64_t key = candidateKey(distanceSquared, slot);
      if (found < k) {
        if (!accept(slot)) return;
        heap[found++] = key;
        std::push_heap(heap, heap + found);
        if (found == k) bound = candidateDistanceSquared(heap[0]);
      } else if (key < heap[0] && accept(slot)) {
        std::pop_heap(heap, heap + k);
        heap[k - 1] = key;
        std::push_heap(heap, heap + k);
        bound = candidateDistanceSquared(heap[0]);
      }
    });
  });
  return found;
}

template <typename Accept>
void PointKdTree::within(const Vec3& p, float radiusSquared, Accept accept, std::vector<uint64_t>& keys) const {
  const PointLanes lanes(p);
  forEachLeaf(p, radiusSquared, [&](uint32_t first, uint32_t end) {
    leafWithin(lanes, first, end, radiusSquared, [&](uint32_t slot, float distanceSquared) {
      if (accept(slot)) keys.push_back(candidateKey(distanceSquared, slot));
    });
  });
}

}  // namespace portico
