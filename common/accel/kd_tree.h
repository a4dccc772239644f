// `kd:median`, `kd:sah`, `kd:bbox`: kd-trees over a cell's triangles, with
// the three split strategies of the paper (§4.2):
//
//   median  the spatial median of the node's longest axis. Builds fastest,
//           traces slowest; stops at the depth and leaf-size limits.
//   sah     the surface area heuristic (MacDonald & Booth 1990, Havran
//           2000), built in O(n log n): binned SAH refined by an exact
//           sweep near the best bin boundary (Wald & Havran 2006) in large
//           nodes, the exact SAH in small ones, with perfect splits
//           (triangles clipped to each node). The fastest to trace: choose
//           it when a cell will take many rays. Stops when no split is
//           cheaper than a leaf.
//   bbox    the bounding-box heuristic (Szécsi 2003): the node's triangle
//           boxes sorted along its longest axis; the split is the box
//           boundary that balances the two sides and cuts the fewest boxes.
//           A compromise between the two in build time.
//
// Parameters (spec "kd:sah,leaf=2,depth=40"; variant sah when none is given):
//   leaf=N          a node of at most N triangles becomes a leaf.
//                   Default 8 (median), 4 (bbox), 0 (sah: the cost model decides).
//   depth=N         the most splits from the root to a leaf, 1..60.
//                   Default 8 + 1.3 log2(triangles) (pbrt's rule).
//   sah only:
//   traversal=C     cost of one traversal step, default 1.
//   intersection=C  cost of one ray-triangle test, default 1.5.
//   empty=F         factor applied to the cost of a split with an empty side
//                   (an empty-space bonus), 0 < F <= 1, default 0.8.
//   bins=N          bins per axis, 2..256, default 32: large nodes first
//                   look for their split among the N - 1 bin boundaries,
//                   then exactly among the triangles' faces near the best.
//
// Hits are identical, bit for bit, to those of `brute`: see kd_traverse.cpp.
#pragma once

#include <string_view>
#include <vector>

#include "common/accel/accelerator.h"
#include "common/accel/kd_node.h"

namespace portico {

enum class KdSplitStrategy { Median, SurfaceArea, BoundingBox };

struct KdTreeOptions {
  KdSplitStrategy strategy = KdSplitStrategy::SurfaceArea;
  int leafSize = -1;  // -1: the strategy's default
  int maxDepth = 0;   // 0: 8 + 1.3 log2(triangles)
  double traversalCost = 1.0;
  double intersectionCost = 1.5;
  double emptyBonus = 0.8;
  int bins = 32;
};

// The deepest tree any option allows (the traversal stack holds one entry per level).
constexpr int kKdMaxDepthLimit = 60;

// Reads the variant and parameters of a `kd` spec.
KdTreeOptions readKdTreeOptions(AcceleratorParameters& parameters);

class KdTree final : public Accelerator {
 public:
  // mesh's arrays must outlive this object.
  explicit KdTree(const MeshView& mesh, const KdTreeOptions& options = {},
                  std::string_view spec = "kd:sah");

  Hit intersect(const Ray& ray) const override;
  bool occluded(const Ray& ray) const override;
  Bounds3 bounds() const override { return tree_.bounds; }
  const AcceleratorStats& stats() const override { return stats_; }

  // The flat tree (for tests, statistics and serialisation).
  const KdTreeData& data() const { return tree_; }

 private:
  template <bool AnyHit>
  bool traverse(const Ray& ray, Hit& best) const;
  template <bool AnyHit>
  bool testEveryTriangle(const Ray& ray, Hit& best) const;

  MeshView mesh_;
  KdTreeData tree_;
  AcceleratorStats stats_;
};

}  // namespace portico
