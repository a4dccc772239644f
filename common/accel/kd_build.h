// What the kd-tree builders share (not part of the public interface): the
// writer that lays out the flat node array, triangle clipping, and the
// reference-based builder that kd:median and kd:bbox plug their split
// choosers into. kd:sah has its own binned builder (kd_sah.cpp).
//
// The invariant every builder keeps, on which the traversal's exactness rests
// (kd_traverse.cpp): every point of every triangle in the tree lies in the
// closed box of some leaf that references that triangle (up to double
// rounding of the clipping, far below the traversal's margin).
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "common/accel/kd_node.h"
#include "common/accel/kd_tree.h"
#include "common/mesh_view.h"

namespace portico {

// The triangles that can be hit, and so go in a tree: finite vertices and
// non-zero area (intersectTriangle never reports a degenerate one).
std::vector<uint32_t> kdTreeTriangles(const MeshView& mesh);

// Resolved options: the strategy's default leaf size and depth filled in.
struct KdBuildLimits {
  uint32_t leafSize = 0;
  uint32_t maxDepth = 0;  // splits from the root to a leaf
};
KdBuildLimits kdBuildLimits(const KdTreeOptions& options, size_t triangleCount);

// Perfect splits: the bounds of the parts of the triangle inside the two
// halves of box at position along axis (closed boxes). The triangle is
// clipped to box by the planes it crosses, then split by the plane, in
// double precision; the bounds are rounded outwards to float and kept
// within the half and the triangle's own bounds. Empty when they do not meet.
void clipTriangleToChildren(const Vec3& v0, const Vec3& v1, const Vec3& v2, const Bounds3& box,
                            int axis, float position, Bounds3& below, Bounds3& above);

// Cheaper and looser: the triangle is split by the plane only (not clipped
// to box first), and the bounds of its parts are cut to box's halves. Just
// as conservative, for box holding the part of the triangle that matters.
void splitTriangleToChildren(const Vec3& v0, const Vec3& v1, const Vec3& v2, const Bounds3& box, int axis,
                             float position, Bounds3& below, Bounds3& above);

// The two halves of box at position along axis.
inline Bounds3 boxBelow(Bounds3 box, int axis, float position) {
  box.hi[axis] = position;
  return box;
}
inline Bounds3 boxAbove(Bounds3 box, int axis, float position) {
  box.lo[axis] = position;
  return box;
}

// Lays out the flat node array depth-first: the two children of a node are
// allocated together, when it is split, so they are neighbours. Counts what
// AcceleratorStats reports.
class KdTreeWriter {
 public:
  explicit KdTreeWriter(KdTreeData& tree);

  // Allocates the root (index 0) and the padding node 1 (see KdTreeData).
  uint32_t root();
  // Makes node an interior node and allocates its two children; returns the
  // index of the first (below) child; the second is that + 1.
  uint32_t split(uint32_t node, int axis, float position);
  // Makes node a leaf holding these triangles; depth counts the root as 1.
  void leaf(uint32_t node, std::span<const uint32_t> triangles, uint32_t depth);

 private:
  KdTreeData& tree_;
};

// kd:sah (kd_sah.cpp).
void buildKdTreeSah(const MeshView& mesh, const KdTreeOptions& options, KdTreeData& tree);

// ---------------------------------------------------------------------------
// Reference-based builder, for split strategies that look at triangle boxes.

// A triangle in a node: its id and the bounds of its part inside the node.
struct KdReference {
  Bounds3 box;
  uint32_t primitive;
};

struct KdSplit {
  int axis = 0;
  float position = 0;
  bool planarBelow = true;  // where triangles lying in the split plane go
};

// Chooses the split of a node, or none to make it a leaf. Called only for
// nodes over the leaf size and above the depth limit.
class KdSplitChooser {
 public:
  virtual ~KdSplitChooser() = default;
  virtual std::optional<KdSplit> choose(std::span<const KdReference> references,
                                        const Bounds3& nodeBox) = 0;
};

// Builds top-down: classifies the references of each node against the split
// its chooser picks, clips straddling triangles to the two children (perfect
// splits), and stops at the leaf size, the depth limit, or at the third
// split on a path that leaves one child with all of its node's triangles.
void buildKdTreeFromReferences(const MeshView& mesh, const KdTreeOptions& options,
                               KdSplitChooser& chooser, KdTreeData& tree);

// The split choosers (kd_median.cpp, kd_bbox.cpp).
class MedianSplitChooser final : public KdSplitChooser {
 public:
  std::optional<KdSplit> choose(std::span<const KdReference> references,
                                const Bounds3& nodeBox) override;
};
class BoundingBoxSplitChooser final : public KdSplitChooser {
 public:
  std::optional<KdSplit> choose(std::span<const KdReference> references,
                                const Bounds3& nodeBox) override;

 private:
  struct Boundary {
    float position;
    uint32_t type;  // 0 end, 1 planar, 2 start: the order at equal positions
  };
  std::optional<KdSplit> chooseOnAxis(std::span<const KdReference> references,
                                      const Bounds3& nodeBox, int axis, uint32_t& cost);
  std::vector<Boundary> boundaries_;  // scratch, reused from node to node
};

// Which side of a split a triangle with this (clipped) box belongs to.
enum class KdSide : uint8_t { Both, Below, Above };
inline KdSide kdSideOf(const Bounds3& box, const KdSplit& split) {
  const float lo = box.lo[split.axis], hi = box.hi[split.axis];
  if (lo == split.position && hi == split.position)
    return split.planarBelow ? KdSide::Below : KdSide::Above;
  if (hi <= split.position) return KdSide::Below;
  if (lo >= split.position) return KdSide::Above;
  return KdSide::Both;
}

}  // namespace portico
