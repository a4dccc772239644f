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
  for (size_t i = 0; i < map.size(); ++i) {
    if (!points[i]) continue;
    const StoredPhoton& photon = map.photon(i);
    const Vec3 normal = -photon.direction;
    positions_.push_back(photon.position);
    normals_.push_back(normal);
    values_.push_back(map.radiance(photon.position, normal, othersScale, k, maxRadius, &points));
  }
  tree_ = PointKdTree(positions_);
  // In node order, a lookup's reads of normals and positions follow its
  // reads of the tree. Ties between equally near points break by the new
  // numbers, which depend only on the points, as the old ones did.
  const std::vector<uint32_t> oldIndex = tree_.renumberInNodeOrder();
  const auto permute = [&](std::vector<Vec3>& values) {
    std::vector<Vec3> permuted(values.size());
    for (size_t i = 0; i < values.size(); ++i) permuted[i] = values[oldIndex[i]];
    values = std::move(permuted);
  };
  permute(positions_);
  permute(normals_);
  permute(values_);
}

bool IrradianceCache::lookup(const Vec3& p, const Vec3& n, Vec3& radiancePerAlbedo) const {
  if (positions_.empty()) return false;
  uint64_t heap[1];
  const auto compatible = [&](uint32_t i) {
    if (dot(normals_[i], n) < kMinNormalCosine) return false;
    const Vec3 offset = positions_[i] - p;
    const float height = dot(offset, n);
    return height * height <= kMaxPlaneSlope * kMaxPlaneSlope * dot(offset, offset);
  };
  if (tree_.search(p, 1, maxRadiusSquared_, compatible, heap) == 0) return false;
  radiancePerAlbedo = values_[PointKdTree::candidateIndex(heap[0])];
  return true;
}

uint64_t IrradianceCache::bytes() const {
  return sizeof(*this) + (positions_.capacity() + normals_.capacity() + values_.capacity()) * sizeof(Vec3) +
         tree_.bytes();
}

}  // namespace portico
