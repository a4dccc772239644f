// A bounding volume hierarchy over lights (Conty Estevez & Kulla 2018; the
// same idea as pbrt-v4's BVHLightSampler): each node holds the box, power
// and emission cone of the lights under it (light_bounds.h). A shading
// point chooses a light by one descent from the root, taking each child in
// proportion to its importance at the point and rescaling the random
// number, so it looks at ~2 log2(n) nodes instead of all n lights, and the
// probability of the light it reaches is the product of the choices made
// on the way: exact, as an unbiased estimate needs. A light whose leaf
// importance is 0 (it faces away from the point, or the point faces away
// from it, or a luminaire sends no light that way) is never chosen; every
// other light keeps a nonzero probability, because a node's importance is
// 0 only when no light under it can reach the point.
//
// The build depends only on the lights and their order (candidate ids,
// sorted): buckets along an axis, ties to the lower axis and bucket,
// stable partitions. Any worker builds the same tree and draws the same
// light for the same (point, normal, u).
#pragma once

#include <cstdint>
#include <vector>

#include "common/scene/store/scene_types.h"
#include "common/transport/light_bounds.h"
#include "common/transport/light_choice.h"

namespace portico {

class LightTree {
 public:
  // Over `candidates` (light ids); lights of no power are left out (they
  // are never chosen). `lights` must outlive the tree (its point
  // luminaires are read from it).
  LightTree(const std::vector<AreaLight>& lights, std::vector<uint32_t> candidates);
  // u in [0,1).
  LightChoice choose(const Vec3& point, const Vec3& normal, float u) const;
  // The probability that choose() returns `light` at this point, for any u
  // (0 for a light not in the tree).
  double probability(const Vec3& point, const Vec3& normal, uint32_t light) const;
  size_t lightCount() const { return leaves_.size(); }
  size_t nodeCount() const { return nodes_.size(); }
  // Levels from the root to the deepest leaf (0: one light).
  uint32_t depth() const { return depth_; }

  // The bounds of one light alone (a point luminaire's cone: the directions
  // its photometric file gives any light to).
  static LightBounds boundsOf(const AreaLight& light);

 private:
  static constexpr uint32_t kInterior = UINT32_MAX;
  struct Node {
    LightBounds bounds;
    PreparedLightBounds prepared;   // of bounds
    uint32_t leaf = kInterior;   // index into leaves_, or kInterior
    uint32_t secondChild = 0;    // interior: the first child is the next node
  };
  // What a leaf's exact test reads of its light.
  struct Leaf {
    uint32_t light = 0;
    Vec3 center, normal;
    Vec3 corners[4];
    int cornerCount = 0;
    const AreaLight* point = nullptr;   // a point luminaire; null for area lights
  };
  uint32_t build(std::vector<uint32_t>& order, size_t begin, size_t end, uint32_t parent, uint32_t level);
  float nodeImportance(uint32_t node, const Vec3& point, const Vec3& normal) const;
  float leafImportance(const Node& node, const Vec3& point, const Vec3& normal) const;

  std::vector<Node> nodes_;          // depth first; node 0 the root
  std::vector<uint32_t> parents_;    // per node (the root's: itself)
  std::vector<Leaf> leaves_;         // in light id order
  std::vector<LightBounds> leafBounds_;
  std::vector<uint32_t> leafNodes_;  // per leaf, its node
  uint32_t depth_ = 0;
};

}  // namespace portico
