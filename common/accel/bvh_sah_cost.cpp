#include "common/accel/bvh_sah_cost.h"

namespace portico {

namespace {

double halfArea(double dx, double dy, double dz) { return dx * dy + dy * dz + dz * dx; }

}  // namespace

template <int Width>
double bvhSahCost(const BvhData<Width>& tree) {
  if (tree.nodes.empty()) return 0;
  const Vec3 extent = tree.bounds.diagonal();
  const double rootArea = halfArea(extent.x, extent.y, extent.z);
  if (!(rootArea > 0)) return 0;
  // Every node's children: a child box's area weighs its node's box test
  // (interior) or its packets (leaf). The root's own test: weight 1.
  double cost = 1;
  for (const BvhNode<Width>& node : tree.nodes)
    for (int k = 0; k < Width; ++k) {
      const double dx = double(node.box[0][1][k]) - node.box[0][0][k];
      if (!(dx >= 0)) continue;   // an unused slot: empty box
      const double area = halfArea(dx, double(node.box[1][1][k]) - node.box[1][0][k],
                                   double(node.box[2][1][k]) - node.box[2][0][k]);
      const uint32_t child = node.child[k];
      cost += area / rootArea * (bvh_child::isLeaf(child) ? bvh_child::packetCount(child) : 1);
    }
  return cost;
}

template double bvhSahCost<4>(const BvhData<4>& tree);
template double bvhSahCost<8>(const BvhData<8>& tree);

}  // namespace portico
