#include "common/transport/photon_map.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <stdexcept>
#include <string>
#include <tuple>

namespace portico {
namespace {

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

}  // namespace

PhotonMap::PhotonMap(std::vector<StoredPhoton> photons) {
  if (photons.size() > kMaxPhotons)
    throw std::invalid_argument("photon map: " + std::to_string(photons.size()) + " photons exceed the limit of " +
                                std::to_string(kMaxPhotons) + " per map; split the cell");
  for (size_t i = 0; i < photons.size(); ++i)
    if (!isFinite(photons[i].position))
      throw std::invalid_argument("photon map: photon of path " + std::to_string(photons[i].pathId) + ", bounce " +
                                  std::to_string(photons[i].bounce) + " has a non-finite position");

  // Canonical order. Sort 32-byte keys rather than 56-byte photons, then
  // permute once; input that is already in order (the usual case) is kept.
  // The keys hold the leading fields of photonKey (maps built from photon
  // tables have pathId 0 and bounce 0 or 1 throughout: the position decides),
  // so the full key is read only for photons at the same position.
  if (!std::is_sorted(photons.begin(), photons.end(), photonLess)) {
    struct SortKey {
      uint64_t pathId;
      uint64_t bounceAndX;   // bounce << 32 | bits(position.x)
      uint64_t yAndZ;        // bits(position.y) << 32 | bits(position.z)
      uint64_t index;
    };
    auto bits = [](float f) { return uint64_t{std::bit_cast<uint32_t>(f)}; };
    std::vector<SortKey> keys(photons.size());
    for (size_t i = 0; i < photons.size(); ++i) {
      const StoredPhoton& p = photons[i];
      keys[i] = {p.pathId, uint64_t{p.bounce} << 32 | bits(p.position.x), bits(p.position.y) << 32 | bits(p.position.z),
                 i};
    }
    std::sort(keys.begin(), keys.end(), [&](const SortKey& a, const SortKey& b) {
      if (a.pathId != b.pathId) return a.pathId < b.pathId;
      if (a.bounceAndX != b.bounceAndX) return a.bounceAndX < b.bounceAndX;
      if (a.yAndZ != b.yAndZ) return a.yAndZ < b.yAndZ;
      return photonKey(photons[a.index]) < photonKey(photons[b.index]);
    });
    photons_.reserve(photons.size());
    for (const SortKey& key : keys) photons_.push_back(photons[key.index]);
  } else {
    photons_ = std::move(photons);
    photons_.shrink_to_fit();
  }

  std::vector<Vec3> positions(photons_.size());
  for (size_t i = 0; i < photons_.size(); ++i) {
    positions[i] = photons_[i].position;
    bounds_.extend(positions[i]);
  }
  tree_ = PointKdTree(positions);
}

float PhotonMap::nearest(const Vec3& p, uint32_t k, float maxRadius, std::vector<uint32_t>& out) const {
  out.clear();
  if (k == 0 || !(maxRadius >= 0)) return 0.0f;
  const float maxRadiusSquared = maxRadius * maxRadius;
  const uint32_t wanted = static_cast<uint32_t>(std::min<size_t>(k, photons_.size()));
  if (wanted == 0) return maxRadiusSquared;

  thread_local std::vector<uint64_t> heap;
  if (heap.size() < wanted) heap.resize(wanted);
  const uint32_t found = tree_.search(p, wanted, maxRadiusSquared, [](uint32_t) { return true; }, heap.data());

  std::sort_heap(heap.data(), heap.data() + found);
  out.resize(found);
  for (uint32_t i = 0; i < found; ++i) out[i] = PointKdTree::candidateIndex(heap[i]);
  return found == k ? PointKdTree::candidateDistanceSquared(heap[found - 1]) : maxRadiusSquared;
}

Vec3 PhotonMap::radiance(const Vec3& p, const Vec3& n, const Vec3& albedo, uint32_t k, float maxRadius,
                         const std::vector<uint8_t>* leftOut) const {
  if (k == 0 || !(maxRadius >= 0)) return {};
  const float maxRadiusSquared = maxRadius * maxRadius;
  const uint32_t wanted = static_cast<uint32_t>(std::min<size_t>(k, photons_.size()));
  if (wanted == 0) return {};

  thread_local std::vector<uint64_t> heap;
  if (heap.size() < wanted) heap.resize(wanted);
  const auto accept = [&](uint32_t i) {
    return dot(photons_[i].direction, n) < kMostFacingAway && !(leftOut && (*leftOut)[i]);
  };
  const uint32_t found = tree_.search(p, wanted, maxRadiusSquared, accept, heap.data());
  if (found == 0) return {};

  // Ascending (distance, index): a fixed summation order.
  std::sort_heap(heap.data(), heap.data() + found);
  float radiusSquared = PointKdTree::candidateDistanceSquared(heap[found - 1]);
  if (found < k && std::isfinite(maxRadiusSquared)) radiusSquared = maxRadiusSquared;
  if (!(radiusSquared > 0)) return {};
  const float radius = std::sqrt(radiusSquared);
  const float discHalfThickness = kDiscThickness * radius;
  const float coneScale = 1.0f / (kConeFilter * radius);

  Vec3 sum;
  for (uint32_t i = 0; i < found; ++i) {
    const StoredPhoton& photon = photons_[PointKdTree::candidateIndex(heap[i])];
    if (std::abs(dot(photon.position - p, n)) > discHalfThickness) continue;
    const float weight = 1.0f - std::sqrt(PointKdTree::candidateDistanceSquared(heap[i])) * coneScale;
    sum += photon.power * weight;
  }
  constexpr float coneNormalisation = 1.0f - 2.0f / (3.0f * kConeFilter);
  return albedo * sum * (1.0f / (kPi * coneNormalisation * kPi * radiusSquared));
}

uint64_t PhotonMap::bytes() const {
  return sizeof(*this) + photons_.capacity() * sizeof(StoredPhoton) + tree_.bytes();
}

}  // namespace portico
