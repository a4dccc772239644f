// Build of the kd-tree's leaf packets (kd_leaf_packets.h) from a built tree.
#include "common/accel/kd_leaf_packets.h"

#include <stdexcept>

namespace portico::kd_leaf_packets {

namespace {

// The sibling pairs of `nodes` (each named by the index of its first node;
// the root and the padding node form pair 0) in the order of the layout
// described at LeafPackets.
std::vector<uint32_t> pairOrder(const std::vector<KdNode>& nodes) {
  constexpr uint32_t kPairsPerLine = 4;
  std::vector<uint32_t> order, pending{0}, treelet;
  order.reserve(nodes.size() / 2);
  uint32_t inLine = 0;
  while (!pending.empty()) {
    const uint32_t root = pending.back();
    pending.pop_back();
    if (inLine == kPairsPerLine) inLine = 0;
    treelet.assign(1, root);
    for (size_t head = 0; head < treelet.size(); ++head) {
      const uint32_t pair = treelet[head];
      order.push_back(pair);
      ++inLine;
      for (uint32_t k = 0; k < 2; ++k)
        if (!(pair == 0 && k == 1) && !nodes[pair + k].isLeaf()) treelet.push_back(nodes[pair + k].firstChild());
      if (inLine == kPairsPerLine) {
        // The line is full: what is left starts subtrees of its own, taken
        // in this order (the stack pops the last pushed first).
        for (size_t i = treelet.size(); i > head + 1; --i) pending.push_back(treelet[i - 1]);
        break;
      }
    }
  }
  return order;
}

}  // namespace

void buildLeafPackets(const MeshView& mesh, const KdTreeData& tree, LeafPackets& out) {
  out.nodes.clear();
  out.packets.clear();
  if (tree.nodes.empty()) return;
  // The nodes in their new places, children indices translated.
  const std::vector<uint32_t> order = pairOrder(tree.nodes);
  std::vector<uint32_t> newFirst(tree.nodes.size() / 2 + 1);
  for (uint32_t i = 0; i < order.size(); ++i) newFirst[order[i] / 2] = 2 * i;
  out.nodes.assign(2 * order.size(), KdNode{});
  for (uint32_t i = 0; i < order.size(); ++i)
    for (uint32_t k = 0; k < 2; ++k) {
      if (order[i] + k >= tree.nodes.size()) continue;
      KdNode node = tree.nodes[order[i] + k];
      if (!node.isLeaf()) node.bits = (newFirst[node.firstChild() / 2] << 2) | uint32_t(node.axis());
      out.nodes[2 * i + k] = node;
    }

  // Count first, so the packets are allocated once.
  size_t total = 0;
  for (const KdNode& node : tree.nodes)
    if (node.isLeaf()) total += (node.triangleCount() + 3) / 4;
  if (total > UINT32_MAX) throw std::length_error("kd-tree: too many leaf packets");
  out.packets.resize(total);

  uint32_t next = 0;
  for (KdNode& node : out.nodes) {
    if (!node.isLeaf()) continue;
    if (node.triangleCount() == 0) {
      node.payload = 0;  // never read; kept in range of the packets
      continue;
    }
    const uint32_t count = node.triangleCount();
    const auto primitiveAt = [&](uint32_t i) {
      return count == 1 ? node.payload : tree.primitives[node.payload + i];
    };
    for (uint32_t first = 0; first < count; first += 4) {
      TrianglePacket& packet = out.packets[next + first / 4];
      for (uint32_t lane = 0; lane < 4; ++lane) {
        // Padding lanes repeat the leaf's last triangle (the test masks them off).
        const uint32_t primitive = primitiveAt(first + lane < count ? first + lane : count - 1);
        Vec3 v[3];
        mesh.triangle(primitive, v[0], v[1], v[2]);
        for (int vertex = 0; vertex < 3; ++vertex) {
          packet.v[vertex][0][lane] = v[vertex].x;
          packet.v[vertex][1][lane] = v[vertex].y;
          packet.v[vertex][2][lane] = v[vertex].z;
        }
        packet.primitive[lane] = primitive;
      }
    }
    node.payload = next;
    next += (count + 3) / 4;
  }
}

}  // namespace portico::kd_leaf_packets
