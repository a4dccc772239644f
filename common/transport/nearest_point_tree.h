// A kd-tree with buckets, for one kind of query: the nearest point that a
// filter accepts, within a radius (the irradiance cache's lookup, made for
// every final-gather hit). Against a tree of one point per node (Jensen's,
// point_kd_tree.h, which the k-nearest photon search uses), a query reads
// fewer, better predicted levels and then runs of points stored side by
// side: 1.4-1.6x as fast on 72 K points on the walls of a room (32 points a
// leaf; 8 and 16 are slower, as is 4).
//
// Layout: flat arrays and no pointers. Nodes in depth-first order (a left
// child follows its parent; the parent holds the right child's index);
// a leaf holds up to kLeafSize points, contiguous in the point array,
// which is in leaf order: callers keep their per-point data in that order
// (order() maps each point's number to the number it was given), so a
// query's filter reads memory next to what the tree reads.
//
// Splits: points on walls, floors and ceilings share a coordinate, and
// queries lie on the same planes. A split never divides points of equal
// coordinate between its sides: each side keeps the exact extent of its
// points on the axis (the left's highest, the right's lowest), so a query
// on a wall's plane, at distance 0 from a plane through the wall, still
// skips the side that holds none of the wall's points. (Splitting equal
// coordinates by index made such queries visit both sides at every level
// that split on the wall's axis: a few per cent of the lookups did most
// of the work.)
//
// Determinism: the tree depends only on the points and their order, and a
// query's answer is the accepted point of least (squared distance in
// float, number): the exact nearest, ties broken by number.
#pragma once

#include <algorithm>
#include <bit>
#include <cstdint>
#include <vector>

#include "common/math.h"
#include "common/transport/point_lanes.h"

namespace portico {

class NearestPointTree {
 public:
  static constexpr uint32_t kLeafSize = 32;
  static constexpr uint32_t kNone = ~uint32_t{0};

  NearestPointTree() = default;
  explicit NearestPointTree(const std::vector<Vec3>& positions);

  size_t size() const { return order_.size(); }
  // For each point number (leaf order), the index it had in `positions`.
  const std::vector<uint32_t>& order() const { return order_; }
  Vec3 position(uint32_t point) const { return {x_[point], y_[point], z_[point]}; }
  uint64_t bytes() const {
    return nodes_.capacity() * sizeof(Node) + (x_.capacity() + y_.capacity() + z_.capacity()) * sizeof(float) +
           order_.capacity() * sizeof(uint32_t);
  }

  // The point of least (squared distance, number) among those with squared
  // distance dot(point - p, point - p) <= maxRadiusSquared that
  // accept(number) lets through; kNone when there is none.
  template <typename Accept>
  uint32_t nearest(const Vec3& p, float maxRadiusSquared, Accept accept) const;

 private:
  // Interior: on axis `axisOrLeaf` (0-2), every point of the left subtree
  // <= leftHigh <= rightLow <= every point of the right one; the left child
  // next in the array, the right one at `index`. Leaf: axisOrLeaf is
  // kLeaf | count << 2, its points [index, index + count).
  struct Node {
    float leftHigh;
    float rightLow;
    uint32_t index;
    uint32_t axisOrLeaf;
  };
  static constexpr uint32_t kLeaf = 3;
  // Far children waiting: one per level. Below kMostSplitDepth a split can
  // leave one side most of the points (a plane of equal coordinates);
  // deeper ones halve them, and < 2^30 points need under 30 more levels.
  static constexpr int kMostDepth = 64;
  static constexpr int kMostSplitDepth = 32;
  static_assert(kMostSplitDepth + 30 < kMostDepth);

  uint32_t build(uint32_t begin, uint32_t end, int depth, std::vector<uint32_t>& items,
                 const std::vector<Vec3>& positions);

  std::vector<Node> nodes_;
  std::vector<float> x_, y_, z_;   // per point, then PointLanes::kLanes - 1 NaN
  std::vector<uint32_t> order_;
};

template <typename Accept>
uint32_t NearestPointTree::nearest(const Vec3& p, float maxRadiusSquared, Accept accept) const {
  if (nodes_.empty()) return kNone;
  uint64_t best = ~uint64_t{0};   // (squared distance bits, number): one comparison orders both
  float bound = maxRadiusSquared;
  // Far children waiting, with the squared distance to their side's
  // extent on the node's axis.
  struct Pending {
    uint32_t node;
    float planeDistanceSquared;
  };
  Pending stack[kMostDepth];
  int pending = 0;
  const PointLanes lanes(p);
  uint32_t node = 0;
  for (;;) {
    const Node* current = &nodes_[node];
    while ((current->axisOrLeaf & 3) != kLeaf) {
      const float coordinate = p[static_cast<int>(current->axisOrLeaf)];
      // How far beyond each side's extent the query lies (<= 0: within).
      const float beyondLeft = coordinate - current->leftHigh;
      const float beforeRight = current->rightLow - coordinate;
      const uint32_t left = static_cast<uint32_t>(current - nodes_.data()) + 1;
      const bool rightNearer = beyondLeft > beforeRight;
      const float farDistance = std::max(rightNearer ? beyondLeft : beforeRight, 0.0f);
      stack[pending++] = {rightNearer ? left : current->index, farDistance * farDistance};
      current = &nodes_[rightNearer ? current->index : left];
    }
    // kLanes points at a time; the last group reads past the leaf (the next
    // leaf's points, or the NaN after the last), which the mask drops.
    const uint32_t end = current->index + (current->axisOrLeaf >> 2);
    for (uint32_t first = current->index; first < end; first += PointLanes::kLanes) {
      float distanceSquared[PointLanes::kLanes];
      uint32_t inside = lanes.within(&x_[first], &y_[first], &z_[first], bound, distanceSquared);
      if (end - first < PointLanes::kLanes) inside &= (1u << (end - first)) - 1;
      for (; inside; inside &= inside - 1) {
        const uint32_t i = first + static_cast<uint32_t>(std::countr_zero(inside));
        const uint64_t key = (uint64_t{std::bit_cast<uint32_t>(distanceSquared[i - first])} << 32) | i;
        if (key < best && accept(i)) {
          best = key;
          bound = distanceSquared[i - first];
        }
      }
    }
    // The next far side that can still hold a point as near (rounding is
    // monotonic: a point beyond a plane never computes nearer than it).
    for (;;) {
      if (pending == 0) return best == ~uint64_t{0} ? kNone : static_cast<uint32_t>(best);
      const Pending next = stack[--pending];
      if (next.planeDistanceSquared <= bound) {
        node = next.node;
        break;
      }
    }
  }
}

}  // namespace portico
