// Where a built kd-tree's nodes lie in memory: a pass after the build
// (kd_tree.cpp runs it on every builder's output), so the builders need not
// care and the traversal reads the same flat nodes (kd_node.h).
#pragma once

#include "common/accel/kd_node.h"

namespace portico {

// Lays the sibling pairs of `tree` out anew; the tree itself (its splits,
// leaves and primitive lists) is unchanged, nodes[0] is still the root and
// nodes[1] padding.
//
// Why: the builders append a node's two children when they split it, depth
// first, so the pair below a node's lower child follows its own, while the
// pair below its upper child lies past the whole lower subtree: a cache
// miss for about every other step of a descent through a tree larger than
// the caches. Here each 64-byte line (four pairs; nodes is line-aligned)
// is filled with a small subtree, breadth first (a pair, the pairs of its
// two children, one grandchild pair), and the subtrees hanging below the
// line follow depth first: every step from a line's first pair to either
// child's pair stays in that line. Measured on the shared 2-core VM (thread
// CPU time, passes interleaved with Embree's): 0-5 % faster at 100K-500K
// triangles, at the edge of the noise; it costs one pass over the nodes.
void layOutInCacheLines(KdTreeData& tree);

}  // namespace portico
