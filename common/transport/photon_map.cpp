#include "common/transport/photon_map.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <stdexcept>
#include <string>
#include <tuple>

namespace portico {
namespace {

constexpr uint32_t kIndexBits = 30;
constexpr uint32_t kIndexMask = (uint32_t{1} << kIndexBits) - 1;

// The canonical photon order: (pathId, bounce), then every other field by
// bit pattern, so that even two deposits with the same key (never produced
// by the tracer, but possible in hand-made input) land in one fixed order.
// Fully identical photons are interchangeable.
auto photonKey(const StoredPhoton& p) {
  auto bits = [](float f) { return std::bit_cast<uint32_t>(f); };
  return std::make_tuple(p.pathId, p.bounce, bits(p.position.x), bits(p.position.y), bits(p.position.z),
                         bits(p.direction.x), bits(p.direction.y), bits(p.direction.z), bits(p.power.x),
                         bits(p.power.y), bits(p.power.z));
}

bool photonLess(const StoredPhoton& a, const StoredPhoton& b) {
  if (a.pathId != b.pathId) return a.pathId < b.pathId;
  if (a.bounce != b.bounce) return a.bounce < b.bounce;
  return photonKey(a) < photonKey(b);
}

// Candidates in the k-NN heap: the squared distance's bits (a non-negative
// float's bits order like the float) above the photon index, so one integer
// comparison orders by (distance, index).
uint64_t candidateKey(float distanceSquared, uint32_t index) {
  return (uint64_t{std::bit_cast<uint32_t>(distanceSquared)} << 32) | index;
}
float candidateDistanceSquared(uint64_t key) { return std::bit_cast<float>(static_cast<uint32_t>(key >> 32)); }
uint32_t candidateIndex(uint64_t key) { return static_cast<uint32_t>(key); }

// Build-only: a photon's position and index, sorted in place by the builder.
struct BuildItem {
  float position[3];
  uint32_t index;
};

// Size of the left subtree of a left-balanced (complete) binary tree of
// `count` nodes: every level full except the last, filled from the left.
size_t leftSubtreeSize(size_t count) {
  if (count <= 1) return 0;
  const int height = std::bit_width(count) - 1;   // levels below the root
  const size_t halfLastLevel = size_t{1} << (height - 1);
  const size_t lastLevel = count - ((size_t{1} << height) - 1);
  return (halfLastLevel - 1) + std::min(lastLevel, halfLastLevel);
}

}  // namespace

PhotonMap::PhotonMap(std::vector<StoredPhoton> photons) {
  if (photons.size() > kMaxPhotons)
    throw std::invalid_argument("photon map: " + std::to_string(photons.size()) + " photons exceed the limit of " +
                                std::to_string(kMaxPhotons) + " per map; split the cell");
  for (size_t i = 0; i < photons.size(); ++i)
    if (!isFinite(photons[i].position))
      throw std::invalid_argument("photon map: photon of path " + std::to_string(photons[i].pathId) + ", bounce " +
                                  std::to_string(photons[i].bounce) + " has a non-finite position");

  // Canonical order. Sort 16-byte keys rather than 56-byte photons, then
  // permute once; input that is already in order (the usual case) is kept.
  if (!std::is_sorted(photons.begin(), photons.end(), photonLess)) {
    struct SortKey {
      uint64_t pathId;
      uint32_t bounce;
      uint32_t index;
    };
    std::vector<SortKey> keys(photons.size());
    for (size_t i = 0; i < photons.size(); ++i)
      keys[i] = {photons[i].pathId, photons[i].bounce, static_cast<uint32_t>(i)};
    std::sort(keys.begin(), keys.end(), [&](const SortKey& a, const SortKey& b) {
      if (a.pathId != b.pathId) return a.pathId < b.pathId;
      if (a.bounce != b.bounce) return a.bounce < b.bounce;
      return photonKey(photons[a.index]) < photonKey(photons[b.index]);
    });
    photons_.reserve(photons.size());
    for (const SortKey& key : keys) photons_.push_back(photons[key.index]);
  } else {
    photons_ = std::move(photons);
    photons_.shrink_to_fit();
  }

  // Left-balanced kd-tree: each subtree's root is the photon of rank
  // leftSubtreeSize(count) along the subset's longest axis (ties by index,
  // a total order), so left children are <= the split and right ones >=.
  const size_t count = photons_.size();
  std::vector<BuildItem> items(count);
  for (size_t i = 0; i < count; ++i) {
    const Vec3& p = photons_[i].position;
    items[i] = {{p.x, p.y, p.z}, static_cast<uint32_t>(i)};
    bounds_.extend(p);
  }
  nodes_.resize(count);

  struct Task {
    size_t begin, end, node;
  };
  std::vector<Task> tasks;
  if (count > 0) tasks.push_back({0, count, 0});
  while (!tasks.empty()) {
    const Task task = tasks.back();
    tasks.pop_back();
    BuildItem* first = items.data() + task.begin;
    const size_t n = task.end - task.begin;

    Bounds3 box;
    for (size_t i = 0; i < n; ++i) box.extend(Vec3(first[i].position[0], first[i].position[1], first[i].position[2]));
    const int axis = box.longestAxis();
    const size_t median = leftSubtreeSize(n);
    std::nth_element(first, first + median, first + n, [axis](const BuildItem& a, const BuildItem& b) {
      if (a.position[axis] != b.position[axis]) return a.position[axis] < b.position[axis];
      return a.index < b.index;
    });

    const BuildItem& root = first[median];
    nodes_[task.node] = {Vec3(root.position[0], root.position[1], root.position[2]),
                         (static_cast<uint32_t>(axis) << kIndexBits) | root.index};
    if (median > 0) tasks.push_back({task.begin, task.begin + median, 2 * task.node + 1});
    if (median + 1 < n) tasks.push_back({task.begin + median + 1, task.end, 2 * task.node + 2});
  }
}

// Exact k-NN over the photons `accept` lets through. Leaves heap[0, result)
// as a max-heap of candidate keys; `heap` holds at least k entries.
template <typename Accept>
uint32_t PhotonMap::search(const Vec3& p, uint32_t k, float maxRadiusSquared, Accept accept, uint64_t* heap) const {
  const size_t nodeCount = nodes_.size();
  uint32_t found = 0;
  // Squared distance a candidate must not exceed: the radius until k are
  // found, then the k-th's distance (equal distance can still win on index).
  float bound = maxRadiusSquared;

  // Far children waiting, with the squared distance to their splitting plane.
  // The depth of a left-balanced tree of < 2^30 nodes is < 31, and pending
  // entries have strictly increasing depths, so 32 slots suffice.
  struct Pending {
    size_t node;
    float planeDistanceSquared;
  };
  Pending stack[32];
  int pending = 0;

  size_t node = 0;
  for (;;) {
    // Descend to a leaf on the query's side, testing each node's photon and
    // leaving the other side for later.
    while (node < nodeCount) {
      const Node& current = nodes_[node];
      const Vec3 offset = current.position - p;
      const float distanceSquared = dot(offset, offset);
      if (distanceSquared <= bound) {
        const uint32_t index = current.axisAndIndex & kIndexMask;
        const uint64_t key = candidateKey(distanceSquared, index);
        if (found < k) {
          if (accept(index)) {
            heap[found++] = key;
            std::push_heap(heap, heap + found);
            if (found == k) bound = candidateDistanceSquared(heap[0]);
          }
        } else if (key < heap[0] && accept(index)) {
          std::pop_heap(heap, heap + k);
          heap[k - 1] = key;
          std::push_heap(heap, heap + k);
          bound = candidateDistanceSquared(heap[0]);
        }
      }
      const int axis = static_cast<int>(current.axisAndIndex >> kIndexBits);
      const float delta = p[axis] - current.position[axis];
      const size_t left = 2 * node + 1;
      const size_t nearChild = delta > 0 ? left + 1 : left;
      const size_t farChild = delta > 0 ? left : left + 1;
      if (farChild < nodeCount) stack[pending++] = {farChild, delta * delta};
      node = nearChild;
    }
    // Next far side that can still hold a candidate. Rounding is monotonic,
    // so a photon beyond the plane never computes closer than the plane.
    for (;;) {
      if (pending == 0) return found;
      const Pending next = stack[--pending];
      if (next.planeDistanceSquared <= bound) {
        node = next.node;
        break;
      }
    }
  }
}

float PhotonMap::nearest(const Vec3& p, uint32_t k, float maxRadius, std::vector<uint32_t>& out) const {
  out.clear();
  if (k == 0 || !(maxRadius >= 0)) return 0.0f;
  const float maxRadiusSquared = maxRadius * maxRadius;
  const uint32_t wanted = static_cast<uint32_t>(std::min<size_t>(k, photons_.size()));
  if (wanted == 0) return maxRadiusSquared;

  thread_local std::vector<uint64_t> heap;
  if (heap.size() < wanted) heap.resize(wanted);
  const uint32_t found = search(p, wanted, maxRadiusSquared, [](uint32_t) { return true; }, heap.data());

  std::sort_heap(heap.data(), heap.data() + found);
  out.resize(found);
  for (uint32_t i = 0; i < found; ++i) out[i] = candidateIndex(heap[i]);
  return found == k ? candidateDistanceSquared(heap[found - 1]) : maxRadiusSquared;
}

Vec3 PhotonMap::radiance(const Vec3& p, const Vec3& n, const Vec3& albedo, uint32_t k, float maxRadius) const {
  if (k == 0 || !(maxRadius >= 0)) return {};
  const float maxRadiusSquared = maxRadius * maxRadius;
  const uint32_t wanted = static_cast<uint32_t>(std::min<size_t>(k, photons_.size()));
  if (wanted == 0) return {};

  thread_local std::vector<uint64_t> heap;
  if (heap.size() < wanted) heap.resize(wanted);
  const uint32_t found = search(
      p, wanted, maxRadiusSquared, [&](uint32_t i) { return dot(photons_[i].direction, n) < 0; }, heap.data());
  if (found == 0) return {};

  // Ascending (distance, index): a fixed summation order.
  std::sort_heap(heap.data(), heap.data() + found);
  float radiusSquared = candidateDistanceSquared(heap[found - 1]);
  if (found < k && std::isfinite(maxRadiusSquared)) radiusSquared = maxRadiusSquared;
  if (!(radiusSquared > 0)) return {};
  const float radius = std::sqrt(radiusSquared);
  const float discHalfThickness = kDiscThickness * radius;
  const float coneScale = 1.0f / (kConeFilter * radius);

  Vec3 sum;
  for (uint32_t i = 0; i < found; ++i) {
    const StoredPhoton& photon = photons_[candidateIndex(heap[i])];
    if (std::abs(dot(photon.position - p, n)) > discHalfThickness) continue;
    const float weight = 1.0f - std::sqrt(candidateDistanceSquared(heap[i])) * coneScale;
    sum += photon.power * weight;
  }
  constexpr float coneNormalisation = 1.0f - 2.0f / (3.0f * kConeFilter);
  return albedo * sum * (1.0f / (kPi * coneNormalisation * kPi * radiusSquared));
}

uint64_t PhotonMap::bytes() const {
  return sizeof(*this) + photons_.capacity() * sizeof(StoredPhoton) + nodes_.capacity() * sizeof(Node);
}

}  // namespace portico
