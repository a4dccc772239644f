#include "common/transport/point_kd_tree.h"

#include <limits>

namespace portico {
namespace {

// Build-only: a point's position and its index in the input.
struct BuildItem {
  float position[3];
  uint32_t index;
};

struct Box {
  float low[3], high[3];
};

Box boundsOf(const BuildItem* items, size_t count) {
  // Six scalars rather than arrays indexed by axis: they stay in registers.
  float lowX = items[0].position[0], lowY = items[0].position[1], lowZ = items[0].position[2];
  float highX = lowX, highY = lowY, highZ = lowZ;
  for (size_t i = 1; i < count; ++i) {
    lowX = std::min(lowX, items[i].position[0]);
    lowY = std::min(lowY, items[i].position[1]);
    lowZ = std::min(lowZ, items[i].position[2]);
    highX = std::max(highX, items[i].position[0]);
    highY = std::max(highY, items[i].position[1]);
    highZ = std::max(highZ, items[i].position[2]);
  }
  return {{lowX, lowY, lowZ}, {highX, highY, highZ}};
}

int longestAxis(const Box& box) {
  int longest = 0;
  for (int axis = 1; axis < 3; ++axis)
    if (box.high[axis] - box.low[axis] > box.high[longest] - box.low[longest]) longest = axis;
  return longest;
}

// Copies from[0, count) to to[0, count): the items below `split` on `axis`
// to the front, the others to the back (in reverse order). Returns how many
// went to the front. No branch on the data: the destination is a select.
size_t partitionBelow(const BuildItem* from, BuildItem* to, size_t count, int axis, float split) {
  size_t front = 0, back = count;
  for (size_t i = 0; i < count; ++i) {
    const bool below = from[i].position[axis] < split;
    to[below ? front : back - 1] = from[i];
    front += below;
    back -= !below;
  }
  return front;
}

}  // namespace

// Splits each node of more than kLeafSize points across the longest axis
// of their bounds, at its midpoint: one pass that copies the node's items
// into the other of two buffers, left ones first. Where the midpoint leaves
// fewer than a quarter of the points on one side (clusters, outliers), and
// below kMostMidpointDepth, it splits at the median instead
// (std::nth_element, in place), which halves them: the depth stays under
// kMostDepth. Points on a plane or in clusters get cells that follow them
// (the midpoint of tight bounds); the tree depends only on the items'
// order. Leaves go to the slots as they are reached, depth-first: slot
// order is leaf order.
class PointKdTreeBuilder {
 public:
  explicit PointKdTreeBuilder(PointKdTree& tree) : tree_(tree) {}

  // Builds the subtree of items[begin, end), with `scratch` as the other
  // buffer, and returns its node.
  uint32_t build(BuildItem* items, BuildItem* scratch, size_t begin, size_t end, int depth) {
    const uint32_t node = static_cast<uint32_t>(tree_.nodes_.size());
    tree_.nodes_.push_back({});
    const size_t count = end - begin;
    if (count <= PointKdTree::kLeafSize) {
      tree_.nodes_[node] = {0.0f, static_cast<uint32_t>(tree_.order_.size()),
                            PointKdTree::kLeaf | static_cast<uint32_t>(count) << 2};
      for (size_t i = begin; i < end; ++i) addSlot(items[i]);
      return node;
    }
    const Box box = boundsOf(items + begin, count);
    const int axis = longestAxis(box);
    const float low = box.low[axis], high = box.high[axis];
    if (low < high && depth < kMostMidpointDepth) {
      // Below the midpoint goes left; when it rounds to `low`, below `high`
      // does: both sides hold a point.
      float split = low + (high - low) * 0.5f;
      if (!(low < split)) split = high;
      const size_t left = partitionBelow(items + begin, scratch + begin, count, axis, split);
      if (std::min(left, count - left) >= count / 4) {
        build(scratch, items, begin, begin + left, depth + 1);   // the left child: node + 1
        const uint32_t right = build(scratch, items, begin + left, end, depth + 1);
        tree_.nodes_[node] = {split, right, static_cast<uint32_t>(axis)};
        return node;
      }
    }
    // The median: every item before it <= it, every one after >= it.
    BuildItem* first = items + begin;
    const size_t median = count / 2;
    std::nth_element(first, first + median, first + count,
                     [axis](const BuildItem& a, const BuildItem& b) { return a.position[axis] < b.position[axis]; });
    const float split = first[median].position[axis];
    build(items, scratch, begin, begin + median, depth + 1);
    const uint32_t right = build(items, scratch, begin + median, end, depth + 1);
    tree_.nodes_[node] = {split, right, static_cast<uint32_t>(axis)};
    return node;
  }

 private:
  // A midpoint split keeps at least a quarter of a node's points on each
  // side, so it can leave three quarters to one child; from this depth on,
  // median splits halve them, and fewer than 2^30 points need under 30
  // more levels.
  static constexpr int kMostMidpointDepth = 40;
  static_assert(kMostMidpointDepth + 30 < PointKdTree::kMostDepth);

  void addSlot(const BuildItem& item) {
    tree_.x_.push_back(item.position[0]);
    tree_.y_.push_back(item.position[1]);
    tree_.z_.push_back(item.position[2]);
    tree_.order_.push_back(item.index);
  }

  PointKdTree& tree_;
};

PointKdTree::PointKdTree(const std::vector<Vec3>& positions) : pointCount_(positions.size()) {
  if (positions.empty()) return;
  std::vector<BuildItem> items(positions.size()), scratch(positions.size());
  for (size_t i = 0; i < positions.size(); ++i)
    items[i] = {{positions[i].x, positions[i].y, positions[i].z}, static_cast<uint32_t>(i)};
  // Leaves hold at least kLeafSize / 4 points (a split keeps a quarter of
  // more than kLeafSize on each side).
  nodes_.reserve(8 * positions.size() / kLeafSize + 1);
  const size_t slots = positions.size() + PointLanes::kLanes - 1;
  for (auto* column : {&x_, &y_, &z_}) column->reserve(slots);
  order_.reserve(positions.size());
  PointKdTreeBuilder(*this).build(items.data(), scratch.data(), 0, items.size(), 0);
  for (auto* column : {&x_, &y_, &z_}) column->resize(slots, std::numeric_limits<float>::quiet_NaN());
  nodes_.shrink_to_fit();
}

uint64_t PointKdTree::bytes() const {
  return nodes_.capacity() * sizeof(Node) + (x_.capacity() + y_.capacity() + z_.capacity()) * sizeof(float) +
         order_.capacity() * sizeof(uint32_t);
}

}  // namespace portico
