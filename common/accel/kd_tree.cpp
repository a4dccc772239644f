// kd-tree: options, and the build (dispatched to the strategy's builder)
// with its statistics. Traversal is in kd_traverse.cpp.
#include "common/accel/kd_tree.h"

#include <chrono>
#include <stdexcept>
#include <string>

#include "common/accel/kd_build.h"
#include "common/accel/kd_layout.h"

namespace portico {

KdTreeOptions readKdTreeOptions(AcceleratorParameters& parameters) {
  KdTreeOptions options;
  const std::string variant = parameters.variant({"median", "sah", "bbox"}, "sah");
  options.strategy = variant == "median" ? KdSplitStrategy::Median
                     : variant == "bbox" ? KdSplitStrategy::BoundingBox
                                         : KdSplitStrategy::SurfaceArea;
  options.leafSize = parameters.integer("leaf", -1, 0, 1 << 20);
  options.maxDepth = parameters.integer("depth", 0, 1, kKdMaxDepthLimit);
  if (options.strategy == KdSplitStrategy::SurfaceArea) {
    options.traversalCost = parameters.positiveNumber("traversal", options.traversalCost);
    options.intersectionCost = parameters.positiveNumber("intersection", options.intersectionCost);
    options.emptyBonus = parameters.positiveNumber("empty", options.emptyBonus);
    options.bins = parameters.integer("bins", options.bins, 2, 256);
    if (options.emptyBonus > 1.0)
      parameters.fail("parameter empty must be a factor in (0, 1] (got " +
                      std::to_string(options.emptyBonus) + ")");
  }
  return options;
}

KdTree::KdTree(const MeshView& mesh, const KdTreeOptions& options, std::string_view spec)
    : mesh_(mesh) {
  const auto start = std::chrono::steady_clock::now();
  // The SAH builder packs a primitive id and an event type in 32 bits.
  if (mesh.triangleCount > KdNode::kMaxIndex)
    throw std::invalid_argument("kd-tree: " + std::to_string(mesh.triangleCount) +
                                " triangles exceed the 2^30 a kd-tree holds; split the cell");
  switch (options.strategy) {
    case KdSplitStrategy::Median: {
      MedianSplitChooser chooser;
      buildKdTreeFromReferences(mesh, options, chooser, tree_);
      break;
    }
    case KdSplitStrategy::BoundingBox: {
      BoundingBoxSplitChooser chooser;
      buildKdTreeFromReferences(mesh, options, chooser, tree_);
      break;
    }
    case KdSplitStrategy::SurfaceArea:
      buildKdTreeSah(mesh, options, tree_);
      break;
  }
  layOutInCacheLines(tree_);  // (a fresh vector of the exact size: nothing to shrink)
  tree_.primitives.shrink_to_fit();

  stats_.spec = std::string(spec);
  stats_.nodes = tree_.nodes.empty() ? 0 : tree_.nodes.size() - 1;  // not the padding node
  stats_.leaves = tree_.leaves;
  stats_.emptyLeaves = tree_.emptyLeaves;
  stats_.triangleReferences = tree_.triangleReferences;
  const uint64_t filledLeaves = tree_.leaves - tree_.emptyLeaves;
  stats_.averageDepth = filledLeaves > 0 ? tree_.depthSum / double(filledLeaves) : 0.0;
  stats_.maxDepth = tree_.maxDepth;
  stats_.bytes = sizeof(*this) + tree_.nodes.capacity() * sizeof(KdNode) +
                 tree_.primitives.capacity() * sizeof(uint32_t);
  stats_.buildMs =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace portico
