#include "common/transport/irradiance_cache.h"

#include <cmath>
#include <stdexcept>

#include "common/rng.h"

namespace portico {

bool IrradianceCache::isPoint(uint32_t photon, uint32_t stride) {
  return mix64(uint64_t{photon} * 0x9e3779b97f4a7c15ull + 0x632be59bd9b4e019ull) % stride == 0;
}

IrradianceCache::IrradianceCache(const PhotonMap& map, uint32_t stride, uint32_t k, float maxRadius)
    : maxRadiusSquared_(maxRadius * maxRadius) {
  if (stride < 2) throw std::invalid_argument("irradiance cache: the stride must be at least 2");
  std::vector<uint8_t> points(map.size());
  for (size_t i = 0; i < map.size(); ++i) points[i] = isPoint(static_cast<uint32_t>(i), stride);
  // The others hold (stride - 1) / stride of the power, on average.
  const Vec3 othersScale(float(stride) / float(stride - 1));
  std::vector<uint32_t> photonOf;   // the map's photon of each point
  for (size_t i = 0; i < map.size(); ++i) {
    if (!points[i]) continue;
    photonOf.push_back(static_cast<uint32_t>(i));
    positions_.push_back(map.photon(i).position);
  }
  tree_ = NearestPointTree(positions_);
  positions_.clear();
  positions_.shrink_to_fit();   // the tree holds them, in its order
  // Estimated in the tree's (leaf) order: consecutive estimates search the
  // same part of the photon map, which stays in cache, and each one's
  // radius is the next one's first guess (PhotonMap::nearest). A lookup's
  // reads of normals and values follow its reads of the tree. Each value
  // depends only on its point, so neither the order nor the guess changes
  // a bit.
  const std::vector<uint32_t>& oldIndex = tree_.order();
  normals_.resize(oldIndex.size());
  values_.resize(oldIndex.size());
  radii_.resize(oldIndex.size());
  float radiusGuess = 0;
  for (size_t point = 0; point < oldIndex.size(); ++point) {
    const StoredPhoton& photon = map.photon(photonOf[oldIndex[point]]);
    normals_[point] = -photon.direction;
    values_[point] =
        map.radiance(photon.position, normals_[point], othersScale, k, maxRadius, &points, &radiusGuess);
    radii_[point] = radiusGuess;   // on return: the radius of this estimate
  }
}

bool IrradianceCache::lookup(const Vec3& p, const Vec3& n, Vec3& radiancePerAlbedo, float* estimateRadius) const {
  const auto compatible = [&](uint32_t i) {
    if (dot(normals_[i], n) < kMinNormalCosine) return false;
    const Vec3 offset = tree_.position(i) - p;
    const float height = dot(offset, n);
    return height * height <= kMaxPlaneSlope * kMaxPlaneSlope * dot(offset, offset);
  };
  const uint32_t point = tree_.nearest(p, maxRadiusSquared_, compatible);
  if (point == NearestPointTree::kNone) return false;
  radiancePerAlbedo = values_[point];
  if (estimateRadius) *estimateRadius = radii_[point];
  return true;
}

uint64_t IrradianceCache::bytes() const {
  return sizeof(*this) + (positions_.capacity() + normals_.capacity() + values_.capacity()) * sizeof(Vec3) +
         radii_.capacity() * sizeof(float) + tree_.bytes();
}

}  // namespace portico
