#include "common/transport/photon_map.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <stdexcept>
#include <string>
#include <tuple>

#include "common/rng.h"
#include "common/transport/order_free_sum.h"

namespace portico {
namespace {

// Every field by bit pattern: the order among photons of equal hash (below).
// Fully identical photons are interchangeable.
bool photonLess(const StoredPhoton& a, const StoredPhoton& b) {
  auto key = [](const StoredPhoton& p) {
    auto bits = [](float f) { return std::bit_cast<uint32_t>(f); };
    return std::make_tuple(p.pathId, p.bounce, bits(p.position.x), bits(p.position.y), bits(p.position.z),
                           bits(p.direction.x), bits(p.direction.y), bits(p.direction.z), bits(p.power.x),
                           bits(p.power.y), bits(p.power.z));
  };
  return key(a) < key(b);
}

// A hash of every field of a photon: equal for identical photons, and
// independent of where the photon sits in the input.
uint64_t photonHash(const StoredPhoton& p) {
  auto bits = [](float f) { return uint64_t{std::bit_cast<uint32_t>(f)}; };
  uint64_t h = mix64(p.pathId ^ 0x9e3779b97f4a7c15ull);
  h = mix64(h ^ (uint64_t{p.bounce} << 32 | bits(p.position.x)));
  h = mix64(h ^ (bits(p.position.y) << 32 | bits(p.position.z)));
  h = mix64(h ^ (bits(p.direction.x) << 32 | bits(p.direction.y)));
  h = mix64(h ^ (bits(p.direction.z) << 32 | bits(p.power.x)));
  return mix64(h ^ (bits(p.power.y) << 32 | bits(p.power.z)));
}

struct HashAndIndex {
  uint64_t hash;
  uint64_t index;
};

// Sorts by hash, stably: an LSD radix sort of 11-bit digits (six passes,
// the six digits' counts taken in one read). On a million photons it takes
// a fraction of std::sort's time, whose comparisons of random hashes
// mispredict about every other branch.
void sortByHash(std::vector<HashAndIndex>& keys) {
  constexpr int kDigitBits = 11, kPasses = 6;
  constexpr uint32_t kDigits = 1u << kDigitBits;
  std::vector<uint32_t> counts(size_t{kPasses} * kDigits, 0);
  for (const HashAndIndex& key : keys)
    for (int pass = 0; pass < kPasses; ++pass) ++counts[pass * kDigits + ((key.hash >> (pass * kDigitBits)) & (kDigits - 1))];
  std::vector<HashAndIndex> scratch(keys.size());
  for (int pass = 0; pass < kPasses; ++pass) {
    uint32_t* offsets = &counts[pass * kDigits];
    uint32_t sum = 0;
    for (uint32_t digit = 0; digit < kDigits; ++digit) {
      const uint32_t count = offsets[digit];
      offsets[digit] = sum;
      sum += count;
    }
    const int shift = pass * kDigitBits;
    for (const HashAndIndex& key : keys) scratch[offsets[(key.hash >> shift) & (kDigits - 1)]++] = key;
    keys.swap(scratch);
  }
}

// The indices of the photons in an order that depends only on the photons
// and not on the order they came in: by the hash of their fields, photons
// of equal hash by every field (photonLess).
std::vector<uint32_t> canonicalOrder(const std::vector<StoredPhoton>& photons) {
  std::vector<HashAndIndex> keys(photons.size());
  for (size_t i = 0; i < photons.size(); ++i) keys[i] = {photonHash(photons[i]), i};
  sortByHash(keys);
  for (size_t begin = 0; begin < keys.size();) {
    size_t end = begin + 1;
    while (end < keys.size() && keys[end].hash == keys[begin].hash) ++end;
    if (end - begin > 1)
      std::sort(keys.begin() + begin, keys.begin() + end, [&](const HashAndIndex& a, const HashAndIndex& b) {
        return photonLess(photons[a.index], photons[b.index]);
      });
    begin = end;
  }
  std::vector<uint32_t> order(photons.size());
  for (size_t i = 0; i < keys.size(); ++i) order[i] = static_cast<uint32_t>(keys[i].index);
  return order;
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

  // The tree over the positions in canonical order, then the photons in the
  // tree's leaf order, copied once: a search reads the photons of a leaf
  // side by side.
  // Both copies read the input in a random order: each prefetches the
  // photon it reads kAhead photons later (about twice as fast on a million).
  constexpr size_t kAhead = 16;
  std::vector<uint32_t> source = canonicalOrder(photons);
  std::vector<Vec3> positions(photons.size());
  for (size_t i = 0; i < photons.size(); ++i) {
    if (i + kAhead < photons.size()) __builtin_prefetch(&photons[source[i + kAhead]]);
    positions[i] = photons[source[i]].position;
    bounds_.extend(positions[i]);
  }
  tree_ = PointKdTree(positions);
  positions = {};
  // Each slot's photon's index in the input.
  std::vector<uint32_t> inputOf(photons.size());
  for (size_t slot = 0; slot < photons.size(); ++slot) inputOf[slot] = source[tree_.order()[slot]];
  source = {};
  tree_.forgetOrder();
  photons_.reserve(photons.size());
  for (size_t slot = 0; slot < photons.size(); ++slot) {
    if (slot + kAhead < photons.size()) __builtin_prefetch(&photons[inputOf[slot + kAhead]]);
    photons_.push_back(photons[inputOf[slot]]);
  }
}

namespace {

// A guessed radius is searched with this margin: the density changes from
// one query to the next nearby one, and a search that finds fewer than k
// starts again.
constexpr float kGuessMargin = 1.15f;
// Widenings before the search gives up on the guess for the heap search
// (a guess far too small, or fewer than k photons in the whole map).
constexpr int kMostWidenings = 3;

float sqrtOrZero(float x) { return x > 0 ? std::sqrt(x) : 0.0f; }

}  // namespace

template <typename Accept>
PhotonMap::Nearest PhotonMap::nearestKeys(const Vec3& p, uint32_t k, float maxRadiusSquared, Accept accept,
                                          float* radiusGuess) const {
  thread_local std::vector<uint64_t> keys;
  Nearest nearest{};
  if (radiusGuess && *radiusGuess > 0) {
    // Every accepted photon within a radius: when k or more, the k nearest
    // of them are the k nearest of all (the others lie farther).
    float radius = *radiusGuess * kGuessMargin;
    for (int widening = 0; widening <= kMostWidenings; ++widening) {
      const float radiusSquared = std::min(radius * radius, maxRadiusSquared);
      keys.clear();
      tree_.within(p, radiusSquared, accept, keys);
      if (keys.size() >= k) {
        std::nth_element(keys.begin(), keys.begin() + (k - 1), keys.end());
        nearest = {keys.data(), k, keys[k - 1]};
        *radiusGuess = sqrtOrZero(PointKdTree::candidateDistanceSquared(nearest.farthest));
        return nearest;
      }
      if (radiusSquared >= maxRadiusSquared) {   // the whole disc: fewer than k there
        nearest = {keys.data(), static_cast<uint32_t>(keys.size()), 0};
        if (!keys.empty()) nearest.farthest = *std::max_element(keys.begin(), keys.end());
        *radiusGuess = sqrtOrZero(maxRadiusSquared);
        return nearest;
      }
      // As far as a uniform density would need, and at least 1.5 times.
      const float needed = keys.empty() ? 2.0f : std::sqrt(float(k) / float(keys.size())) * kGuessMargin;
      radius *= std::clamp(needed, 1.5f, 4.0f);
    }
  }
  if (keys.size() < k) keys.resize(k);
  nearest.keys = keys.data();
  nearest.found = tree_.search(p, k, maxRadiusSquared, accept, keys.data());
  nearest.farthest = nearest.found > 0 ? keys[0] : 0;   // the max-heap's top
  if (radiusGuess)
    *radiusGuess =
        sqrtOrZero(nearest.found == k ? PointKdTree::candidateDistanceSquared(nearest.farthest) : maxRadiusSquared);
  return nearest;
}

float PhotonMap::nearest(const Vec3& p, uint32_t k, float maxRadius, std::vector<uint32_t>& out,
                         float* radiusGuess) const {
  out.clear();
  if (k == 0 || !(maxRadius >= 0)) return 0.0f;
  const float maxRadiusSquared = maxRadius * maxRadius;
  const uint32_t wanted = static_cast<uint32_t>(std::min<size_t>(k, photons_.size()));
  if (wanted == 0) return maxRadiusSquared;

  const Nearest nearest = nearestKeys(p, wanted, maxRadiusSquared, [](uint32_t) { return true; }, radiusGuess);
  std::sort(nearest.keys, nearest.keys + nearest.found);   // nearest first, ties by index
  out.resize(nearest.found);
  for (uint32_t i = 0; i < nearest.found; ++i) out[i] = PointKdTree::candidateSlot(nearest.keys[i]);
  return nearest.found == k ? PointKdTree::candidateDistanceSquared(nearest.farthest) : maxRadiusSquared;
}

Vec3 PhotonMap::radiance(const Vec3& p, const Vec3& n, const Vec3& albedo, uint32_t k, float maxRadius,
                         const std::vector<uint8_t>* leftOut, float* radiusGuess) const {
  if (k == 0 || !(maxRadius >= 0)) return {};
  const float maxRadiusSquared = maxRadius * maxRadius;
  const uint32_t wanted = static_cast<uint32_t>(std::min<size_t>(k, photons_.size()));
  if (wanted == 0) return {};

  const auto accept = [&](uint32_t i) {
    return dot(photons_[i].direction, n) < kMostFacingAway && !(leftOut && (*leftOut)[i]);
  };
  const Nearest nearest = nearestKeys(p, wanted, maxRadiusSquared, accept, radiusGuess);
  if (nearest.found == 0) return {};

  float radiusSquared = PointKdTree::candidateDistanceSquared(nearest.farthest);
  if (nearest.found < k && std::isfinite(maxRadiusSquared)) radiusSquared = maxRadiusSquared;
  if (!(radiusSquared > 0)) return {};
  const float radius = std::sqrt(radiusSquared);
  const float discHalfThickness = kDiscThickness * radius;
  const float coneScale = 1.0f / (kConeFilter * radius);

  // Each photon's share, then their sum, which does not depend on the
  // order the search found them in.
  thread_local std::vector<Vec3> shares;
  shares.clear();
  float largest = 0;
  for (uint32_t i = 0; i < nearest.found; ++i) {
    const StoredPhoton& photon = photons_[PointKdTree::candidateSlot(nearest.keys[i])];
    if (std::abs(dot(photon.position - p, n)) > discHalfThickness) continue;
    const float weight = 1.0f - std::sqrt(PointKdTree::candidateDistanceSquared(nearest.keys[i])) * coneScale;
    shares.push_back(photon.power * weight);
    for (int c = 0; c < 3; ++c) largest = std::max(largest, std::abs(shares.back()[c]));
  }
  OrderFreeSum sum(largest, static_cast<uint32_t>(shares.size()));
  for (const Vec3& share : shares) sum.add(share);
  constexpr float coneNormalisation = 1.0f - 2.0f / (3.0f * kConeFilter);
  return albedo * sum.total() * (1.0f / (kPi * coneNormalisation * kPi * radiusSquared));
}

uint64_t PhotonMap::bytes() const {
  return sizeof(*this) + photons_.capacity() * sizeof(StoredPhoton) + tree_.bytes();
}

}  // namespace portico
