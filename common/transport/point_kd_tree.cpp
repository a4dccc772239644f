#include "common/transport/point_kd_tree.h"

namespace portico {
namespace {

// Build-only: a point's position and index, sorted in place by the builder.
struct BuildItem {
  float position[3];
  uint32_t index;
};

// Size of the left subtree of a left-balanced (complete) binary tree of
// `count` nodes: every level full except the last, filled from the left.
size_t leftSubtreeSize(size_t count) {
  if (count <= 1) return 0;
  const int height = std::bit_width(count) - 1;   // levels below the root
  const size_t halfLastLevel = size_t{1} << (height - 1);
  const size_t lastLevel = count - ((size_t{1} << height) - 1);
  return (halfLastLevel - 1) + std::min(lastLevel, halfLastLevel);
}

}  // namespace

PointKdTree::PointKdTree(const std::vector<Vec3>& positions) {
  // Each subtree's root is the point of rank leftSubtreeSize(count) along
  // the subset's longest axis (ties by index, a total order), so left
  // children are <= the split and right ones >=.
  const size_t count = positions.size();
  std::vector<BuildItem> items(count);
  for (size_t i = 0; i < count; ++i)
    items[i] = {{positions[i].x, positions[i].y, positions[i].z}, static_cast<uint32_t>(i)};
  nodes_.resize(count);

  struct Task {
    size_t begin, end, node;
  };
  std::vector<Task> tasks;
  if (count > 0) tasks.push_back({0, count, 0});
  while (!tasks.empty()) {
    const Task task = tasks.back();
    tasks.pop_back();
    BuildItem* first = items.data() + task.begin;
    const size_t n = task.end - task.begin;

    Bounds3 box;
    for (size_t i = 0; i < n; ++i) box.extend(Vec3(first[i].position[0], first[i].position[1], first[i].position[2]));
    const int axis = box.longestAxis();
    const size_t median = leftSubtreeSize(n);
    std::nth_element(first, first + median, first + n, [axis](const BuildItem& a, const BuildItem& b) {
      if (a.position[axis] != b.position[axis]) return a.position[axis] < b.position[axis];
      return a.index < b.index;
    });

    const BuildItem& root = first[median];
    nodes_[task.node] = {Vec3(root.position[0], root.position[1], root.position[2]),
                         (static_cast<uint32_t>(axis) << kIndexBits) | root.index};
    if (median > 0) tasks.push_back({task.begin, task.begin + median, 2 * task.node + 1});
    if (median + 1 < n) tasks.push_back({task.begin + median + 1, task.end, 2 * task.node + 2});
  }
}

std::vector<uint32_t> PointKdTree::renumberInNodeOrder() {
  std::vector<uint32_t> oldIndex(nodes_.size());
  for (size_t node = 0; node < nodes_.size(); ++node) {
    oldIndex[node] = nodes_[node].axisAndIndex & kIndexMask;
    nodes_[node].axisAndIndex = (nodes_[node].axisAndIndex & ~kIndexMask) | static_cast<uint32_t>(node);
  }
  return oldIndex;
}

}  // namespace portico
