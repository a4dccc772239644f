// The cache-line layout of a built kd-tree's nodes (kd_layout.h).
#include "common/accel/kd_layout.h"

#include <cstdint>
#include <vector>

namespace portico {

namespace {

// The sibling pairs of `nodes` (each named by the index of its first node;
// the root and the padding node form pair 0) in the order of the layout.
std::vector<uint32_t> pairOrder(const std::vector<KdNode, CacheLineAllocator<KdNode>>& nodes) {
  constexpr uint32_t kPairsPerLine = 4;  // 64 bytes of 8-byte nodes
  std::vector<uint32_t> order, pending{0}, treelet;
  order.reserve(nodes.size() / 2);
  uint32_t inLine = 0;
  while (!pending.empty()) {
    const uint32_t root = pending.back();
    pending.pop_back();
    if (inLine == kPairsPerLine) inLine = 0;
    // Breadth first from `root` while the line has room (a subtree that
    // ends early leaves the rest of its line to the next one).
    treelet.assign(1, root);
    for (size_t head = 0; head < treelet.size(); ++head) {
      const uint32_t pair = treelet[head];
      order.push_back(pair);
      ++inLine;
      for (uint32_t k = 0; k < 2; ++k)
        if (!(pair == 0 && k == 1) && !nodes[pair + k].isLeaf()) treelet.push_back(nodes[pair + k].firstChild());
      if (inLine == kPairsPerLine) {
        // The line is full: the pairs left start subtrees of their own, in
        // this order (the stack pops the last pushed first).
        for (size_t i = treelet.size(); i > head + 1; --i) pending.push_back(treelet[i - 1]);
        break;
      }
    }
  }
  return order;
}

}  // namespace

void layOutInCacheLines(KdTreeData& tree) {
  if (tree.nodes.empty()) return;
  const std::vector<uint32_t> order = pairOrder(tree.nodes);
  std::vector<uint32_t> newFirst(tree.nodes.size() / 2);  // new index of each old pair
  for (uint32_t i = 0; i < order.size(); ++i) newFirst[order[i] / 2] = 2 * i;
  std::vector<KdNode, CacheLineAllocator<KdNode>> nodes(tree.nodes.size());
  for (uint32_t i = 0; i < order.size(); ++i)
    for (uint32_t k = 0; k < 2; ++k) {
      KdNode node = tree.nodes[order[i] + k];
      // Only the children's index changes: the split's bits stay as they are.
      if (!node.isLeaf()) node.bits = (newFirst[node.firstChild() / 2] << 2) | uint32_t(node.axis());
      nodes[2 * i + k] = node;
    }
  tree.nodes.swap(nodes);
}

}  // namespace portico
