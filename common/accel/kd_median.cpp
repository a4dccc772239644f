// kd:median: the split is the spatial median of the node's longest axis
// (the paper's first strategy). It looks at no triangle, so choosing costs
// O(1) per node; only distributing the triangles costs (O(n log n) overall).
// The builder stops at the leaf size and depth limits.
#include <utility>

#include "common/accel/kd_build.h"

namespace portico {

std::optional<KdSplit> MedianSplitChooser::choose(std::span<const KdReference>,
                                                  const Bounds3& nodeBox) {
  // The longest axis first; a box too small to halve in float on that axis
  // (the midpoint rounds onto a face) tries the next longest.
  const Vec3 extent = nodeBox.diagonal();
  int axes[3] = {0, 1, 2};
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2 - i; ++j)
      if (extent[axes[j + 1]] > extent[axes[j]]) std::swap(axes[j], axes[j + 1]);
  for (int axis : axes) {
    const float lo = nodeBox.lo[axis], hi = nodeBox.hi[axis];
    const float middle = lo + 0.5f * (hi - lo);
    if (middle > lo && middle < hi) return KdSplit{axis, middle, true};
  }
  return std::nullopt;
}

}  // namespace portico
