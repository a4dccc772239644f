// A left-balanced kd-tree over points, for exact k-nearest-neighbour
// queries: the photon map's tree, and the irradiance cache's.
//
// Layout: one flat array and no pointers, in implicit heap order (the
// children of node i are 2i+1 and 2i+2), one node per point, 16 bytes: its
// position and one word packing the split axis (2 bits) with the point's
// index (30 bits) — Jensen's layout with Tungsten's packed word. It can be
// written out and read back as-is.
//
// Determinism: splits and queries break ties by point index, so the tree
// and every query result depend only on the points and their order.
#pragma once

#include <algorithm>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "common/math.h"

namespace portico {

class PointKdTree {
 public:
  // The most points one tree holds: node words keep 30 bits of index.
  static constexpr size_t kMaxPoints = (size_t{1} << 30) - 1;

  PointKdTree() = default;
  // Builds over positions[0 .. n); the caller checks n <= kMaxPoints.
  explicit PointKdTree(const std::vector<Vec3>& positions);

  size_t size() const { return nodes_.size(); }
  // Renumbers the points in node order (node i holds point i from then on)
  // and returns, for each new number, the old one. Callers permute their
  // per-point arrays with it, so that a search reads them close to the
  // tree nodes it reads.
  std::vector<uint32_t> renumberInNodeOrder();
  uint64_t bytes() const { return nodes_.capacity() * sizeof(Node); }

  // Candidates of a k-NN search: the squared distance's bits (a non-negative
  // float's bits order like the float) above the point index, so one integer
  // comparison orders by (distance, index).
  static uint64_t candidateKey(float distanceSquared, uint32_t index) {
    return (uint64_t{std::bit_cast<uint32_t>(distanceSquared)} << 32) | index;
  }
  static float candidateDistanceSquared(uint64_t key) {
    return std::bit_cast<float>(static_cast<uint32_t>(key >> 32));
  }
  static uint32_t candidateIndex(uint64_t key) { return static_cast<uint32_t>(key); }

  // Exact k-NN over the points `accept(index)` lets through, with squared
  // distance dot(point - p, point - p) (in float) <= maxRadiusSquared.
  // Leaves heap[0, result) as a max-heap of candidate keys; `heap` holds at
  // least k entries (k >= 1).
  template <typename Accept>
  uint32_t search(const Vec3& p, uint32_t k, float maxRadiusSquared, Accept accept, uint64_t* heap) const;

 private:
  static constexpr uint32_t kIndexBits = 30;
  static constexpr uint32_t kIndexMask = (uint32_t{1} << kIndexBits) - 1;
  struct Node {
    Vec3 position;
    uint32_t axisAndIndex;   // split axis in the top 2 bits, point index below
  };
  static_assert(sizeof(Node) == 16);

  std::vector<Node> nodes_;
};

template <typename Accept>
uint32_t PointKdTree::search(const Vec3& p, uint32_t k, float maxRadiusSquared, Accept accept, uint64_t* heap) const {
  const size_t nodeCount = nodes_.size();
  uint32_t found = 0;
  // Squared distance a candidate must not exceed: the radius until k are
  // found, then the k-th's distance (equal distance can still win on index).
  float bound = maxRadiusSquared;

  // Far children waiting, with the squared distance to their splitting plane.
  // The depth of a left-balanced tree of < 2^30 nodes is < 31, and pending
  // entries have strictly increasing depths, so 32 slots suffice.
  struct Pending {
    size_t node;
    float planeDistanceSquared;
  };
  Pending stack[32];
  int pending = 0;

  size_t node = 0;
  for (;;) {
    // Descend to a leaf on the query's side, testing each node's point and
    // leaving the other side for later.
    while (node < nodeCount) {
      const Node& current = nodes_[node];
      const Vec3 offset = current.position - p;
      const float distanceSquared = dot(offset, offset);
      if (distanceSquared <= bound) {
        const uint32_t index = current.axisAndIndex & kIndexMask;
        const uint64_t key = candidateKey(distanceSquared, index);
        if (found < k) {
          if (accept(index)) {
            heap[found++] = key;
            std::push_heap(heap, heap + found);
            if (found == k) bound = candidateDistanceSquared(heap[0]);
          }
        } else if (key < heap[0] && accept(index)) {
          std::pop_heap(heap, heap + k);
          heap[k - 1] = key;
          std::push_heap(heap, heap + k);
          bound = candidateDistanceSquared(heap[0]);
        }
      }
      const int axis = static_cast<int>(current.axisAndIndex >> kIndexBits);
      const float delta = p[axis] - current.position[axis];
      const size_t left = 2 * node + 1;
      const size_t nearChild = delta > 0 ? left + 1 : left;
      const size_t farChild = delta > 0 ? left : left + 1;
      if (farChild < nodeCount) stack[pending++] = {farChild, delta * delta};
      node = nearChild;
    }
    // Next far side that can still hold a candidate. Rounding is monotonic,
    // so a point beyond the plane never computes closer than the plane.
    for (;;) {
      if (pending == 0) return found;
      const Pending next = stack[--pending];
      if (next.planeDistanceSquared <= bound) {
        node = next.node;
        break;
      }
    }
  }
}

}  // namespace portico
