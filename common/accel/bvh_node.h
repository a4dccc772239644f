// The flat form of `bvh`: what the builder (bvh_build.cpp) writes and the
// traversal (bvh_traverse.cpp) reads. Index-based, pointer-free.
//
// A node holds the boxes of its Width children side by side per axis and
// side (structure of arrays), so one SIMD load brings the same bound of four
// children and all of them are tested at once; a node fills whole cache
// lines (4-wide: 2 lines, 8-wide: 4). The child words come first, sharing
// the first line with the boxes, so the box test's own loads bring them and
// choosing a child never waits for a line of its own.
//
// A child is a 32-bit word: an interior child is the index of its node; a
// leaf has bit 31 set, the number of its triangle packets less one in bits
// 28-30 and the index of its first packet in bits 0-27. A leaf's triangles
// are copies of the mesh's vertices, bit for bit, four to a packet (the
// last padded with its leaf's last triangle), in the layout of the 4-wide
// triangle test (grid_traversal.h), so a leaf is one contiguous read. An
// unused slot has an empty box (+inf low, -inf high), which no ray enters.
#pragma once

#include <sys/mman.h>

#include <cstdint>
#include <new>
#include <vector>

#include "common/accel/grid_traversal.h"
#include "common/math.h"
#include "common/mesh_view.h"

namespace portico {

template <int Width>
struct alignas(64) BvhNode {
  uint32_t child[Width];
  float box[3][2][Width];   // [axis][0: low, 1: high][child]
};
static_assert(sizeof(BvhNode<4>) == 128 && sizeof(BvhNode<8>) == 256);

namespace bvh_child {
constexpr uint32_t kLeafBit = 0x80000000u;
constexpr uint32_t kMaxPackets = 8;                      // per leaf: 3 bits
constexpr uint32_t kMaxFirstPacket = (1u << 28) - 1;     // 2^28 packets: a billion triangles
inline bool isLeaf(uint32_t child) { return (child & kLeafBit) != 0; }
inline uint32_t leaf(uint32_t firstPacket, uint32_t packets) {
  return kLeafBit | ((packets - 1) << 28) | firstPacket;
}
inline uint32_t firstPacket(uint32_t child) { return child & kMaxFirstPacket; }
inline uint32_t packetCount(uint32_t child) { return ((child >> 28) & 7) + 1; }
}  // namespace bvh_child

// The deepest a tree may be (root = depth 1): the builder splits ranges at
// their median once it is kForcedMedianDepth deep, which halves them at
// every level after; the traversal's stack holds Width - 1 entries a level.
constexpr int kBvhForcedMedianDepth = 40;
constexpr int kBvhMaxDepth = kBvhForcedMedianDepth + 33;

// Allocator of the tree's arrays. An array of 4 MiB or more is rounded up
// to whole 2 MiB pages, aligned to them, and asks for transparent huge
// pages (madvise): a ray's nodes and leaves lie anywhere in the tree, and
// past the reach of the processor's second-level TLB (2 048 entries of 4 KiB
// on Zen 3) every one of them would cost a page walk too; 500k-triangle
// trees (29 MiB) trace photon rays ~20 % faster so. Smaller arrays stay on
// 4 KiB pages: a worker's many small cells keep reusing freed memory
// (common/util/heap_reuse.h) rather than having the kernel zero fresh 2 MiB
// pages (from 512 KiB, 100k-triangle trees trace 2-5 % faster in `portico
// bench accel`, but the octagon's photon pass builds its cells' trees in
// twice the time: grid_traversal.h: LargeArrayAllocator).
namespace bvh_memory {
constexpr size_t kHugePage = size_t(2) << 20;
// `bytes` rounded up to whole huge pages: what allocateHugePages takes.
inline size_t hugePageBytes(size_t bytes) { return (bytes + kHugePage - 1) / kHugePage * kHugePage; }
// hugePageBytes(bytes) aligned to 2 MiB, on transparent huge pages (a hint:
// failure only costs speed); freed by freeHugePages with the same bytes.
inline void* allocateHugePages(size_t bytes) {
  void* pointer = ::operator new(hugePageBytes(bytes), std::align_val_t{kHugePage});
  madvise(pointer, hugePageBytes(bytes), MADV_HUGEPAGE);
  return pointer;
}
inline void freeHugePages(void* pointer, size_t bytes) noexcept {
  ::operator delete(pointer, hugePageBytes(bytes), std::align_val_t{kHugePage});
}
}  // namespace bvh_memory

template <typename T>
struct BvhArrayAllocator {
  using value_type = T;
  static constexpr size_t kHugeFrom = size_t(4) << 20;
  static constexpr std::align_val_t kCacheLine{64};

  BvhArrayAllocator() = default;
  template <typename U>
  BvhArrayAllocator(const BvhArrayAllocator<U>&) noexcept {}

  T* allocate(size_t count) {
    const size_t bytes = count * sizeof(T);
    if (bytes < kHugeFrom) return static_cast<T*>(::operator new(bytes, kCacheLine));
    return static_cast<T*>(bvh_memory::allocateHugePages(bytes));
  }
  void deallocate(T* pointer, size_t count) noexcept {
    const size_t bytes = count * sizeof(T);
    if (bytes < kHugeFrom)
      ::operator delete(pointer, kCacheLine);
    else
      bvh_memory::freeHugePages(pointer, bytes);
  }
  template <typename U>
  bool operator==(const BvhArrayAllocator<U>&) const noexcept { return true; }
};

// A built BVH: nodes[0] is the root; a mesh with no triangle that can be hit
// has no nodes.
template <int Width>
struct BvhData {
  std::vector<BvhNode<Width>, BvhArrayAllocator<BvhNode<Width>>> nodes;
  // Aligned to a cache line, so that every packet (160 bytes) spans three
  // lines, never four.
  std::vector<grid_traversal::TrianglePacket, BvhArrayAllocator<grid_traversal::TrianglePacket>> packets;
  Bounds3 bounds;   // of the triangles held: the root's box

  uint64_t leaves = 0;
  uint64_t triangles = 0;   // held: every finite, non-degenerate triangle of the mesh
  double depthSum = 0;      // over leaves, root = depth 1
  uint32_t maxDepth = 0;
};

// Builds the tree of the mesh's finite, non-degenerate triangles (the others
// never hit: intersectTriangle) by binned SAH (bvh_build.cpp).
template <int Width>
BvhData<Width> buildBvh(const MeshView& mesh);

}  // namespace portico
