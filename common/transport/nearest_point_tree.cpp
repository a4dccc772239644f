#include "common/transport/nearest_point_tree.h"

#include <algorithm>
#include <limits>
#include <numeric>
#include <stdexcept>

namespace portico {

NearestPointTree::NearestPointTree(const std::vector<Vec3>& positions) {
  if (positions.size() >= (size_t{1} << 30))
    throw std::length_error("nearest-point tree: more than 2^30 points");
  std::vector<uint32_t> items(positions.size());
  std::iota(items.begin(), items.end(), 0u);
  nodes_.reserve(2 * (positions.size() / kLeafSize + 1));
  if (!items.empty()) build(0, static_cast<uint32_t>(items.size()), 0, items, positions);
  order_ = std::move(items);
  const size_t slots = order_.empty() ? 0 : order_.size() + PointLanes::kLanes - 1;
  for (auto* column : {&x_, &y_, &z_}) column->assign(slots, std::numeric_limits<float>::quiet_NaN());
  for (size_t i = 0; i < order_.size(); ++i) {
    const Vec3& position = positions[order_[i]];
    x_[i] = position.x;
    y_[i] = position.y;
    z_[i] = position.z;
  }
}

// Splits [begin, end) of `items` across its box's longest axis until a
// leaf's worth is left; returns the node's index. The median (ties by
// index: a total order) picks the split value; the points equal to it go
// together to the side that leaves the halves nearer even. Below
// kMostSplitDepth; deeper, or when every point has the median's value, the
// split is at the median itself, which halves the points (the depth stays
// under kMostDepth). Recursion is fine at that depth.
uint32_t NearestPointTree::build(uint32_t begin, uint32_t end, int depth, std::vector<uint32_t>& items,
                                 const std::vector<Vec3>& positions) {
  const uint32_t node = static_cast<uint32_t>(nodes_.size());
  nodes_.push_back({});
  if (end - begin <= kLeafSize) {
    nodes_[node] = {0.0f, 0.0f, begin, kLeaf | ((end - begin) << 2)};
    return node;
  }
  Bounds3 box;
  for (uint32_t i = begin; i < end; ++i) box.extend(positions[items[i]]);
  const int axis = box.longestAxis();
  const auto coordinate = [&](uint32_t item) { return positions[item][axis]; };
  const uint32_t median = begin + (end - begin) / 2;
  std::nth_element(items.begin() + begin, items.begin() + median, items.begin() + end, [&](uint32_t a, uint32_t b) {
    if (coordinate(a) != coordinate(b)) return coordinate(a) < coordinate(b);
    return a < b;
  });
  const float value = coordinate(items[median]);
  uint32_t middle = median;
  if (depth < kMostSplitDepth) {
    // [begin, median) holds the points below the value and some equal to
    // it, [median, end) the rest: gather the equal ones next to the median.
    const auto below = [&](uint32_t item) { return coordinate(item) < value; };
    const auto notAbove = [&](uint32_t item) { return !(coordinate(item) > value); };
    const uint32_t lowEnd = static_cast<uint32_t>(
        std::stable_partition(items.begin() + begin, items.begin() + median, below) - items.begin());
    const uint32_t highBegin = static_cast<uint32_t>(
        std::stable_partition(items.begin() + median, items.begin() + end, notAbove) - items.begin());
    // Both sides must hold a point; of the two cuts, the one nearer the median.
    const bool lowCut = lowEnd > begin, highCut = highBegin < end;
    if (lowCut && (!highCut || median - lowEnd <= highBegin - median))
      middle = lowEnd;
    else if (highCut)
      middle = highBegin;
  }
  float leftHigh = coordinate(items[begin]), rightLow = coordinate(items[end - 1]);
  for (uint32_t i = begin; i < middle; ++i) leftHigh = std::max(leftHigh, coordinate(items[i]));
  for (uint32_t i = middle; i < end; ++i) rightLow = std::min(rightLow, coordinate(items[i]));
  build(begin, middle, depth + 1, items, positions);
  const uint32_t right = build(middle, end, depth + 1, items, positions);
  nodes_[node] = {leftHigh, rightLow, right, static_cast<uint32_t>(axis)};
  return node;
}

}  // namespace portico
