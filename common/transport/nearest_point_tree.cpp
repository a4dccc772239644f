#include "common/transport/nearest_point_tree.h"

#include <algorithm>
#include <numeric>
#include <stdexcept>

namespace portico {

NearestPointTree::NearestPointTree(const std::vector<Vec3>& positions) {
  if (positions.size() >= (size_t{1} << 30))
    throw std::length_error("nearest-point tree: more than 2^30 points");
  std::vector<uint32_t> items(positions.size());
  std::iota(items.begin(), items.end(), 0u);
  nodes_.reserve(2 * (positions.size() / kLeafSize + 1));
  if (!items.empty()) build(0, static_cast<uint32_t>(items.size()), items, positions);
  order_ = std::move(items);
  positions_.resize(order_.size());
  for (size_t i = 0; i < order_.size(); ++i) positions_[i] = positions[order_[i]];
}

// Splits [begin, end) of `items` at the median of its box's longest axis
// (ties by index: a total order) until a leaf's worth is left; returns the
// node's index. Depth is log2(n / kLeafSize): recursion is fine.
uint32_t NearestPointTree::build(uint32_t begin, uint32_t end, std::vector<uint32_t>& items,
                                 const std::vector<Vec3>& positions) {
  const uint32_t node = static_cast<uint32_t>(nodes_.size());
  nodes_.push_back({});
  if (end - begin <= kLeafSize) {
    nodes_[node] = {0.0f, begin, kLeaf | ((end - begin) << 2)};
    return node;
  }
  Bounds3 box;
  for (uint32_t i = begin; i < end; ++i) box.extend(positions[items[i]]);
  const int axis = box.longestAxis();
  const uint32_t middle = begin + (end - begin) / 2;
  std::nth_element(items.begin() + begin, items.begin() + middle, items.begin() + end,
                   [&](uint32_t a, uint32_t b) {
                     if (positions[a][axis] != positions[b][axis]) return positions[a][axis] < positions[b][axis];
                     return a < b;
                   });
  // Left holds points <= split, right points >= split.
  const float split = positions[items[middle]][axis];
  build(begin, middle, items, positions);
  const uint32_t right = build(middle, end, items, positions);
  nodes_[node] = {split, right, static_cast<uint32_t>(axis)};
  return node;
}

}  // namespace portico
