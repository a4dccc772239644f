// The surface area heuristic's cost of a built `bvh` tree: the expected
// work of a ray that enters the root, in the units the builder weighs
// (bvh_build.cpp): one wide node's box test, or one packet of four
// triangles, each taken with the probability that a ray entering the root
// enters its box (its area over the root's). A measure of the tree's
// quality that needs no rays: builders are compared by it.
#pragma once

#include "common/accel/bvh_node.h"

namespace portico {

// 0 for a tree with no nodes.
template <int Width>
double bvhSahCost(const BvhData<Width>& tree);

}  // namespace portico
